//
// State_END_FuncRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
