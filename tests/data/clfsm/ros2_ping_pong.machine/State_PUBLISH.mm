// State_PUBLISH.mm: the glue MiEditLLFSM generates
