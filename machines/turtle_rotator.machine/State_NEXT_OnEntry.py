answer = result.result()
how = "reached" if answer.status == GoalStatus.STATUS_SUCCEEDED else "aborted at"
print(f"{how} heading {headings[index]:+.4f}, turned {answer.result.delta:+.4f}")
index += 1
goal = None
