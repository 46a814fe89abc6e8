// State_TURN_RIGHT.mm: the glue MiEditLLFSM generates
