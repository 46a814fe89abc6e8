// State_TEST.mm: the glue MiEditLLFSM generates
