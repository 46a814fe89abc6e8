// State_END.mm: the glue MiEditLLFSM generates
