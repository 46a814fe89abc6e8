suspend("ros2_blind_turtle_bot");
