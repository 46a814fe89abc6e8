//
// State_SUSPEND_BOT_VarRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
