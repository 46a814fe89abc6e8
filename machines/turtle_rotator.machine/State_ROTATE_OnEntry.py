goal = sent.result()
result = goal.get_result_async()
