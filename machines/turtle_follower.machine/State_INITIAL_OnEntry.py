ros.init()
node = ros.Node("turtle_follower")
spawner = node.create_client(Spawn, "/spawn")
# started beside turtlesim by `llfsm launch`, the follower may be up first: give turtlesim a few
# seconds to appear (in one `llfsm run` with --node turtlesim the service is there at once)
spawner.wait_for_service(timeout_sec=5.0)
# as the course does: ros2 service call /spawn turtlesim/srv/Spawn "{x: 6.0, y: 5.0, name: 'turtle2'}"
spawned = spawner.call_async(Spawn.Request(x=6.0, y=5.0, theta=0.0, name="turtle2"))
spawn_code = ros.spin_until_future_complete(node, spawned, timeout_sec=5.0)
leader = node.create_subscription(Pose, "/turtle1/pose", None, 1)
me = node.create_subscription(Pose, "/turtle2/pose", None, 1)
cmd = node.create_publisher(Twist, "/turtle2/cmd_vel", 10)
