//
// State_STRAIGHT.h
//
// Automatically created through MiCASE -- do not change manually!
//
#include "CLState.h"

namespace FSM { namespace CLM { namespace FSMros2_wall_turtle_bot { namespace State {
            class STRAIGHT: public CLState
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
                class Transition_1: public CLTransition
                {
                public:
                    Transition_1(int toState = 2): CLTransition(toState) {}
                    virtual bool check(CLMachine *, CLState *) const;
                };
                CLTransition *_transitions[2];
            public:
                virtual int numberOfTransitions() const { return 2; }
#               include "State_STRAIGHT_Variables.h"
            };
} } } }
