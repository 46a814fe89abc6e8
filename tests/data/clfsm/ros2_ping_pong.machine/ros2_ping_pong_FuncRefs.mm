//
// ros2_ping_pong_FuncRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
