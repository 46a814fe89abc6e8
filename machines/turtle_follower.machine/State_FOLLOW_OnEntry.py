# One step of the control loop; the self-transition re-enters this state every period_ms.
if leader.latest is not None and me.latest is not None:
    dx = leader.latest.x - me.latest.x
    dy = leader.latest.y - me.latest.y
    distance = math.hypot(dx, dy)
    twist = Twist()  # zero: what the follower sends inside the dead zone
    if distance > tolerance:
        # Improvement 1, rotation: wrap the heading error into [-pi, pi] so the turtle always
        # turns the short way instead of sometimes going ~360 degrees round.
        error = math.atan2(dy, dx) - me.latest.theta
        error = math.atan2(math.sin(error), math.cos(error))
        # Improvement 3, convergence: sqrt laws (finite-time control) push harder than a
        # proportional law near the target, and min/max bound the commands.
        speed = min(max_linear, k_linear * math.sqrt(distance - tolerance))
        # no driving off sideways or backwards while the heading is still far off
        twist.linear.x = speed * max(0.0, math.cos(error))
        turn = k_angular * math.copysign(math.sqrt(abs(error)), error)
        twist.angular.z = max(-max_angular, min(max_angular, turn))
    # Improvement 2, overlap: inside the tolerance the command stays zero (a dead zone), so the
    # turtles neither oscillate nor chase a heading that is undefined when they overlap.
    cmd.publish(twist)
