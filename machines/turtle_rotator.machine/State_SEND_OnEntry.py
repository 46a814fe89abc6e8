sent = client.send_goal_async(RotateAbsolute.Goal(theta=headings[index]))
