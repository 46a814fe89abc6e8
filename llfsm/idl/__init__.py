"""The interface toolchain: `.msg` / `.srv` definitions read (`package`), turned into Python
message classes and their DDS forms (`ddsgen`, templates/), for the shipped packages (`make
msgs`) and for users' packages found through `paths` and the import hook in llfsm.msgs.

Nothing at run time imports this for a shipped message: the generated modules carry everything.
"""
