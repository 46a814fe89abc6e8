//
// State_WAIT_AND_COUNT_FuncRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
