//
// ros2_turtle_suspend_resume_FuncRefs.mm
//
// Automatically created through MiCASE -- do not change manually!
//
