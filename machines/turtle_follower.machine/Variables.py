node: ros.Node
leader: ros.Subscription  # PULL reader of /turtle1/pose: the newest pose when we want it
me: ros.Subscription  # PULL reader of /turtle2/pose
cmd: ros.Publisher
spawn_code: ros.FutureReturnCode
max_linear: float = 2.0  # m/s: the bound on forward speed
max_angular: float = 4.0  # rad/s: the bound on turning speed
tolerance: float = 0.6  # m: the dead zone; closer than this the follower rests
k_linear: float = 1.5
k_angular: float = 4.0
period_ms: int = 50  # the control loop runs at 20 Hz
