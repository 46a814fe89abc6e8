//
// ros2_ping_pong.h
//
// Automatically created through MiCASE -- do not change manually!
//
#include "CLMachine.h"

namespace FSM { namespace CLM {
    class ros2_ping_pong: public CLMachine {
        CLState *_states[5];
    public:
        virtual int numberOfStates() const { return 5; }
#       include "ros2_ping_pong_Variables.h"
    };
} }
