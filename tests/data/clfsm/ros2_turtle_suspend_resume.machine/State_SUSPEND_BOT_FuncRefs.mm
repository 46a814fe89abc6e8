//
// State_SUSPEND_BOT_FuncRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
