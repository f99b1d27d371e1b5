"""The simulated arm without ROS: the sim node adapts it (nodes/sim.py).

    arm.py        Arm: what the sim node asks of an arm (follow, stop, lock, step, reset)
                  and what comes back (Following, Locked, Scheduled, Refused, Step); the
                  seam for another backend beside the kinematic one (MuJoCo, issue 37)
    kinematic.py  KinematicArm: follows its commands exactly, slowed to its speed limit;
                  locks (scheduled ones where the command puts the arm), brakes, resets
    clearance.py  ClearanceMonitor: collisions, counted once each, and the smallest
                  clearance, screened cheaply and measured exactly
    initial.py    where the arm starts: the clearest configuration at the task start

It imports the core and execution/ (the lock-angle bound, shared with the executor) only:
no rclpy, no message type (test/unit/test_layers.py).
"""
