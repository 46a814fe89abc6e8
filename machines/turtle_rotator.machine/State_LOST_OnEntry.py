# A server that goes away mid-goal never answers: its goal's futures stay undone.  Its
# endpoints leaving (at once, or after the DDS lease if its process died) is what says so.
print(f"the server of {client.action_name} went away before heading {headings[index]:+.4f} was reached")
