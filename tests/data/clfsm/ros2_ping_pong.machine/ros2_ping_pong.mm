//
// ros2_ping_pong.mm
//
// Automatically created through MiCASE -- do not change manually!
//
#include "ros2_ping_pong.h"
#include "State_INITIAL.h"
#include "State_PUBLISH.h"
#include "State_WAIT_AND_COUNT.h"
#include "State_END.h"
#include "State_SUSPENDED.h"

ros2_ping_pong::ros2_ping_pong(int mid, const char *name): CLMachine(mid, name)
{
	_states[0] = new FSMros2_ping_pong::State::INITIAL;
	_states[1] = new FSMros2_ping_pong::State::PUBLISH;
	_states[2] = new FSMros2_ping_pong::State::WAIT_AND_COUNT;
	_states[3] = new FSMros2_ping_pong::State::END;
	_states[4] = new FSMros2_ping_pong::State::SUSPENDED;

	setSuspendState(_states[4]);            // set suspend state
	setInitialState(_states[0]);            // set initial state
}
