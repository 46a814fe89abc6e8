// State_INITIAL.mm: the glue MiEditLLFSM generates
