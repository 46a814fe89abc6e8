//
// State_WAIT_AND_COUNT_VarRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
