"""Time the planner against the exhaustive grid baseline on the same random scenes.

    .venv/bin/python benchmarks/plan_vs_grid.py [--scenes 30] [--seed 0] [--cells 256] [--json F]

The same as `ftplan bench`; see ftplan_ros/bench/recall.py for what is measured.
"""

import sys

from ftplan_ros.cli import main

if __name__ == '__main__':
    sys.exit(main(['bench', *sys.argv[1:]]))
