//
// State_SERVICE_FAILS_FuncRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
