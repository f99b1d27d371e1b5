"""The benchmarks behind `ftplan bench`: random and crowded scenes, recall, spatial arms.

`scenes` draws random planar scenes and referees a plan by brute force; `crowded` builds
scenes crowded next to the arm's own start and goal while a plan still exists; `recall`
measures the planner's recall and time against the existence decision on a joint grid
(core/grid/existence.py) in one run; `spatial` does the same for 7-joint arms; `reach`
checks the plans for an arm standing somewhere (core/planning/reachable.py) against brute
force.
"""
