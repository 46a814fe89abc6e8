//
// State_TURN_RIGHT_Variables.h
//
// Automatically created through MiCASE -- do not change manually!
//
