count += 1
print(f"count = {count} at state {state_name()}")
