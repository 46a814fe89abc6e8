print(f"{machine_name()} starts, counting to {limit}")
