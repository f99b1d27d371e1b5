"""Plans shared by the planning tests, each made once per session."""

import numpy as np
import pytest
from ftplan_testing import robot_config

from ftplan_ros.core import plan
from ftplan_ros.core.model.scene import Scene, Task
from ftplan_ros.core.planning.drill import run_drill

# Found beforehand with a throwaway search (random collision-free configurations q1,
# q2 = q1 + N(0, 0.5), task FK(q1) -> FK(q2)), written here as plain numbers.
PANDA_POSITION = Task((0.384714, 0.110461, 0.998025), (0.559901, 0.527879, 0.39444),
                      goal_tolerance=0.005)


@pytest.fixture(scope='session')
def panda_position():
    """The Panda on a position task (redundancy 4: planned on curves), and its plan."""
    scene = Scene(robot_config('panda', 'position')).with_task(PANDA_POSITION)
    return scene, plan(scene)


@pytest.fixture(scope='session')
def panda_position_drill(panda_position):
    """100 drill trials of the Panda's position plan."""
    scene, result = panda_position
    return run_drill(scene, result, 100, np.random.default_rng(11))
