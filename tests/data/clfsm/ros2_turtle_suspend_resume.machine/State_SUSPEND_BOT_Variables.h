//
// State_SUSPEND_BOT_Variables.h
//
// Automatically created through MiCASE -- do not change manually!
//
