//
// State_END.h
//
// Automatically created through MiCASE -- do not change manually!
//
#include "CLState.h"

namespace FSM { namespace CLM { namespace FSMros2_blind_turtle_bot { namespace State {
            class END: public CLState
            {
                class OnEntry: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class OnExit: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class Internal: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class OnSuspend: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class OnResume: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                CLTransition *_transitions[0];
            public:
                virtual int numberOfTransitions() const { return 0; }
#               include "State_END_Variables.h"
            };
} } } }
