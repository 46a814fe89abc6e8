//
// ros2_wall_turtle_bot.h
//
// Automatically created through MiCASE -- do not change manually!
//
#include "CLMachine.h"

namespace FSM { namespace CLM {
    class ros2_wall_turtle_bot: public CLMachine {
        CLState *_states[9];
    public:
        virtual int numberOfStates() const { return 9; }
#       include "ros2_wall_turtle_bot_Variables.h"
    };
} }
