//
// ros2_blind_turtle_bot_FuncRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
