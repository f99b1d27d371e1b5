"""The executor's logic without ROS: the nodes adapt it (nodes/executor.py).

A plain class with verbs that take the moment of the call and return actions, so that
every outcome of an execution has a unit test without DDS:

    executor.py  Executor: the verbs (hold, start, on_joint_state, on_lock, on_obstacles,
                 tick, reset, use_robot, abort); refuses a run, remembers locks while idle
    run.py       Run: one execution from the request to done or failed: approach θ_s,
                 the nominal path, a lock's stop and recovery, new obstacles
    recovery.py  the way on after a lock (the core's recover in S_F, or a path to the goal
                 with the joints left), and why there is none
    watchdog.py  the arm's last joint states, and the timeouts of a run
    command.py   a timed command under way, and where on it the arm is
    actions.py   what the verbs take (Moment) and return (Command, Stop, Status, Rejected)
    state.py     the held plan, the record of a run, its phases
    options.py   the options (the node's parameters), the obstacles seen, the wording
    locks.py     the locked joints, remembered until repaired; the bound on a lock's angle
    motion.py    timing a joint path, progress along one (the injector and sim use it too)

It imports the core only: no rclpy, no message type (test/unit/test_layers.py).
"""
