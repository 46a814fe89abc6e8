// State_RESUME.mm: the glue MiEditLLFSM generates
