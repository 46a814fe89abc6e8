//
// ros2_turtle_suspend_resume.mm
//
// Automatically created through MiCASE -- do not change manually!
//
#include "ros2_turtle_suspend_resume.h"
#include "State_INITIAL.h"
#include "State_RESUME.h"
#include "State_SUSPEND_BOT.h"
#include "State_END.h"
#include "State_SUSPENDED.h"

ros2_turtle_suspend_resume::ros2_turtle_suspend_resume(int mid, const char *name): CLMachine(mid, name)
{
	_states[0] = new FSMros2_turtle_suspend_resume::State::INITIAL;
	_states[1] = new FSMros2_turtle_suspend_resume::State::RESUME;
	_states[2] = new FSMros2_turtle_suspend_resume::State::SUSPEND_BOT;
	_states[3] = new FSMros2_turtle_suspend_resume::State::END;
	_states[4] = new FSMros2_turtle_suspend_resume::State::SUSPENDED;

	setSuspendState(_states[4]);            // set suspend state
	setInitialState(_states[0]);            // set initial state
}
