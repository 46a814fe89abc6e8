//
// State_TURN_RIGHT_VarRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
