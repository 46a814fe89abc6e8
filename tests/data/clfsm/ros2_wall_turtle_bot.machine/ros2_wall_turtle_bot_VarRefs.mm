//
// ros2_wall_turtle_bot_VarRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
ros2_wall_turtle_bot *_m = static_cast<ros2_wall_turtle_bot *>(_machine);
