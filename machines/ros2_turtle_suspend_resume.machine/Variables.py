bot: str = "ros2_blind_turtle_bot"  # the machine this one suspends and resumes, by name
