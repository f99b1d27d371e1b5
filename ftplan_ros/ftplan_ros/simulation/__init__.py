"""The simulated arm without ROS: the sim node adapts it (nodes/sim.py).

    arm.py        Arm: what the sim node asks of an arm (follow, stop, lock, step, reset)
                  and what comes back (Following, Locked, Scheduled, Refused, Step, Contact)
    kinematic.py  KinematicArm: follows its commands exactly, slowed to its speed limit;
                  locks (scheduled ones where the command puts the arm), brakes, resets
    mujoco_arm.py MujocoArm: MuJoCo's physics; servos track a KinematicArm's commanded
                  path, a lock is a brake, contacts from MuJoCo's collision detection
    mujoco_model.py  the robot and obstacles as MJCF; PhysicsOptions (gains, torque
                  limits, masses) from config/robots/*_mujoco.yaml
    clearance.py  ClearanceMonitor: collisions, counted once each, and the smallest
                  clearance, screened cheaply and measured exactly
    initial.py    where the arm starts: the clearest configuration at the task start

It imports the core, execution/ (the lock-angle bound, shared with the executor) and
mujoco only: no rclpy, no message type (test/unit/test_layers.py).
"""
