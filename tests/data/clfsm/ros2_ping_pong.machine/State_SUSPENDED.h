//
// State_SUSPENDED.h
//
// Automatically created through MiCASE -- do not change manually!
//
#include "CLState.h"

namespace FSM { namespace CLM { namespace FSMros2_ping_pong { namespace State {
            class SUSPENDED: public CLState
            {
                class OnEntry: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class OnExit: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class Internal: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class OnSuspend: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class OnResume: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                CLTransition *_transitions[0];
            public:
                virtual int numberOfTransitions() const { return 0; }
#               include "State_SUSPENDED_Variables.h"
            };
} } } }
