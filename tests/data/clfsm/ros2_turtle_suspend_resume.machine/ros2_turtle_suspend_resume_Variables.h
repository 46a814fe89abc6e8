//
// ros2_turtle_suspend_resume_Variables.h
//
// Automatically created through MiCASE -- do not change manually!
//
