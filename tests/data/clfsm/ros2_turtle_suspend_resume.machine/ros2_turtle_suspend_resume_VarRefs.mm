//
// ros2_turtle_suspend_resume_VarRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
ros2_turtle_suspend_resume *_m = static_cast<ros2_turtle_suspend_resume *>(_machine);
