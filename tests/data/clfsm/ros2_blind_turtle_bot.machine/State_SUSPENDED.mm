// State_SUSPENDED.mm: the glue MiEditLLFSM generates
