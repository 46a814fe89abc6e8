count: int = 0
publisher_: ros.Publisher  # starts as None, created in INITIAL
node: ros.Node
