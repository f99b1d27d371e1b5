"""Default names of ftplan's topics and services (CONTRACT.md); remap them with --ros-args."""

JOINT_STATES = '/joint_states'
ROBOT_DESCRIPTION = '/robot_description'
ROBOT_DESCRIPTION_SEMANTIC = '/robot_description_semantic'  # MoveIt's SRDF (issue 33)
OBSTACLES = '/ftplan/obstacles'
PLAN_SERVICE = '/ftplan/plan'
START_CONFIGURATION = '/ftplan/plan/start_configuration'
TRAJECTORY = '/ftplan/plan/trajectory'
FAILURE_SURFACE = '/ftplan/plan/failure_surface'
APPROACH = '/ftplan/plan/approach'  # how the arm gets to θ_s from where it stood (issue 10)
PLAN_MARKERS = '/ftplan/plan/markers'
PLAN_INFO = '/ftplan/plan/info'  # the plan status, latched: robot, obstacles, task (issue 33)
LOCKED_JOINT = '/ftplan/locked_joint'
EXECUTE_SERVICE = '/ftplan/execute'
JOINT_COMMAND = '/ftplan/joint_command'
DIAGNOSTICS = '/diagnostics'
RESET_SERVICE = '~/reset'  # sim and executor: forget the locked joints

PLANNER_NODE = 'ftplan_planner'
EXECUTOR_NODE = 'ftplan_executor'
SIM_NODE = 'ftplan_sim'
INJECTOR_NODE = 'ftplan_injector'
RECORDER_NODE = 'ftplan_recorder'
