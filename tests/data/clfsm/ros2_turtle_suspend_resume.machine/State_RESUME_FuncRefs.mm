//
// State_RESUME_FuncRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
