//
// State_SERVICE_FAILS_Variables.h
//
// Automatically created through MiCASE -- do not change manually!
//
