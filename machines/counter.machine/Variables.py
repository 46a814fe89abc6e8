count: int = 0  # how many times COUNT was entered
limit: int = 5
