// State_WAIT_AND_COUNT.mm: the glue MiEditLLFSM generates
