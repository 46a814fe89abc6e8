//
// State_TURN_RIGHT_FuncRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
