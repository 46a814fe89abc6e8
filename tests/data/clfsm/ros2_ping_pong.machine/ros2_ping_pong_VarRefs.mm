//
// ros2_ping_pong_VarRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
ros2_ping_pong *_m = static_cast<ros2_ping_pong *>(_machine);
