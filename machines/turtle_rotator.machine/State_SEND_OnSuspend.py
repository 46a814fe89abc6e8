# A goal on its way when the machine is suspended is canceled as soon as it is accepted.
sent.add_done_callback(lambda done: done.result().accepted and done.result().cancel_goal_async())
