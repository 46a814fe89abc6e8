//
// ros2_blind_turtle_bot.mm
//
// Automatically created through MiCASE -- do not change manually!
//
#include "ros2_blind_turtle_bot.h"
#include "State_INITIAL.h"
#include "State_STRAIGHT.h"
#include "State_TURN_RIGHT.h"
#include "State_END.h"
#include "State_SUSPENDED.h"

ros2_blind_turtle_bot::ros2_blind_turtle_bot(int mid, const char *name): CLMachine(mid, name)
{
	_states[0] = new FSMros2_blind_turtle_bot::State::INITIAL;
	_states[1] = new FSMros2_blind_turtle_bot::State::STRAIGHT;
	_states[2] = new FSMros2_blind_turtle_bot::State::TURN_RIGHT;
	_states[3] = new FSMros2_blind_turtle_bot::State::END;
	_states[4] = new FSMros2_blind_turtle_bot::State::SUSPENDED;

	setSuspendState(_states[4]);            // set suspend state
	setInitialState(_states[0]);            // set initial state
}
