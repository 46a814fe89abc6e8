//
// State_SERVICE_FAILS_VarRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
