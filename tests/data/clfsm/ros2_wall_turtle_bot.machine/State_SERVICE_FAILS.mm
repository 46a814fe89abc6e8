// State_SERVICE_FAILS.mm: the glue MiEditLLFSM generates
