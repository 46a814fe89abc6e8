# Suspending a machine stops its ringlets, not its goals: turtlesim would go on turning the
# turtle.  So the goal under way is canceled here, and sent again when the machine resumes.
if not result.done():
    goal.cancel_goal_async()
