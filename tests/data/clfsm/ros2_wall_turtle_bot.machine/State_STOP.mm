// State_STOP.mm: the glue MiEditLLFSM generates
