// State_BACK.mm: the glue MiEditLLFSM generates
