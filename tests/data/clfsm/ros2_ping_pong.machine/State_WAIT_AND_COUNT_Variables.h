//
// State_WAIT_AND_COUNT_Variables.h
//
// Automatically created through MiCASE -- do not change manually!
//
