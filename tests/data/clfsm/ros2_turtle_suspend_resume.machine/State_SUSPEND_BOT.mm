// State_SUSPEND_BOT.mm: the glue MiEditLLFSM generates
