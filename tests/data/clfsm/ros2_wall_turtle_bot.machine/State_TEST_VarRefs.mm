//
// State_TEST_VarRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
