//
// State_TEST_Variables.h
//
// Automatically created through MiCASE -- do not change manually!
//
