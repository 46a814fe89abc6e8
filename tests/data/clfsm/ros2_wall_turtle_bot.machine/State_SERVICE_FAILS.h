//
// State_SERVICE_FAILS.h
//
// Automatically created through MiCASE -- do not change manually!
//
#include "CLState.h"

namespace FSM { namespace CLM { namespace FSMros2_wall_turtle_bot { namespace State {
            class SERVICE_FAILS: public CLState
            {
                class OnEntry: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class OnExit: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class Internal: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class OnSuspend: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class OnResume: public CLAction { virtual void perform(CLMachine *, CLState *) const; };
                class Transition_0: public CLTransition
                {
                public:
                    Transition_0(int toState = 7): CLTransition(toState) {}
                    virtual bool check(CLMachine *, CLState *) const;
                };
                CLTransition *_transitions[1];
            public:
                virtual int numberOfTransitions() const { return 1; }
#               include "State_SERVICE_FAILS_Variables.h"
            };
} } } }
