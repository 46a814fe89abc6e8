"""What moves the bus's messages: in process only (`inproc`, the default) or over DDS (`dds`).

Nodes and machines use `llfsm.ros`; a transport is chosen per run (`llfsm run --transport`,
or `LLFSM_TRANSPORT`) and never seen by machine code.  See `base.Transport` for the interface.
"""
