// State_STRAIGHT.mm: the glue MiEditLLFSM generates
