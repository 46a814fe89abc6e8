//
// ros2_wall_turtle_bot_FuncRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
