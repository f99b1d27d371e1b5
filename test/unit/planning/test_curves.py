"""Plans on curves of frozen joints (core/planning/curves.py), for redundancy 2 or more."""

import numpy as np
import pytest
from ftplan_testing import SCENES, robot_config, within_limits

from ftplan_ros.core import ManifoldCache, PlannerOptions, load_scene, plan
from ftplan_ros.core.io.scene_file import parse_scene
from ftplan_ros.core.model.robot import task_errors, task_residuals
from ftplan_ros.core.model.scene import Scene, Task
from ftplan_ros.core.planning.curves import CurveSearch, FrozenJoints
from ftplan_ros.core.planning.drill import run_drill

FROZEN = ((1, 4), (0.3, -0.5))  # panda_joint2 and panda_joint5 held at these angles [rad]


def test_frozen_joints_are_the_whole_robot_with_those_joints_held(rng):
    whole = robot_config('panda', 'position')
    frozen = FrozenJoints(whole, *FROZEN)
    assert frozen.joint_names == tuple(name for j, name in enumerate(whole.joint_names)
                                       if j not in FROZEN[0])
    thetas = rng.uniform(frozen.limits[:, 0], frozen.limits[:, 1], (10, frozen.n_joints))
    expanded = frozen.expand(thetas)
    assert np.all(expanded[:, list(FROZEN[0])] == FROZEN[1])
    assert np.array_equal(np.delete(expanded, FROZEN[0], axis=1), thetas)
    assert np.allclose(frozen.forward_kinematics(thetas), whole.forward_kinematics(expanded))
    assert np.allclose(frozen.link_frames(thetas), whole.link_frames(expanded))
    x = whole.forward_kinematics(rng.uniform(whole.limits[:, 0], whole.limits[:, 1]))
    assert np.allclose(task_errors(frozen, x, thetas), task_errors(whole, x, expanded))
    _, whole_jacobian = task_residuals(whole, x, expanded)
    _, jacobian = task_residuals(frozen, x, thetas)
    assert np.allclose(jacobian, np.delete(whole_jacobian, FROZEN[0], axis=2))


# Found beforehand with a throwaway search, as test_planner.py's tasks of spatial arms.
PANDA_AXIS = Task((-0.093301, -0.244672, 1.037889, -0.570841, -0.720894, -0.393004),
                  (-0.223709, -0.056523, 0.933914, 0.2307, -0.813728, -0.533502),
                  goal_tolerance=0.005, orientation_tolerance=0.01)

PLANAR_4R = {'robot': {'type': 'planar', 'link_lengths': [1.0, 0.8, 0.6, 0.4],
                       'link_radius': 0.02},
             'obstacles': [{'type': 'sphere', 'center': [1.6, -0.9], 'radius': 0.25},
                           {'type': 'sphere', 'center': [-1.0, 1.0], 'radius': 0.3}],
             'task': {'start': [2.2, 0.0], 'goal': [0.5, 1.5], 'goal_tolerance': 0.01}}


def test_a_position_plan_runs_on_a_curve_of_frozen_joints(panda_position):
    scene, result = panda_position
    assert result.feasible, result.reason
    curve = result.stats['curve']
    assert len(curve['frozen_joints']) == 3  # r = 7 - 3 = 4: three frozen, one to trace
    frozen = [scene.robot.joint_names.index(name) for name in curve['frozen_joints']]
    values = np.asarray(curve['frozen_values_rad'])
    paths = result.surface.paths
    assert np.all(paths[..., frozen] == values)
    assert np.all(result.nominal_path[:, frozen] == values)
    assert result.tolerated_joints == tuple(range(7))
    assert within_limits(scene.robot, paths)


def test_a_planar_4r_plans_on_a_curve():
    scene = parse_scene(PLANAR_4R)
    result = plan(scene)
    assert result.feasible, result.reason
    curve = result.stats['curve']
    assert len(curve['frozen_joints']) == 1 and curve['criterion']
    frozen = scene.robot.joint_names.index(curve['frozen_joints'][0])
    assert np.all(result.surface.paths[..., frozen] == curve['frozen_values_rad'][0])
    assert scene.task.reached(task_errors(scene.robot, scene.task.goal,
                                          result.nominal_path[-1]))


def test_an_axis_plan_on_the_panda():
    scene = Scene(robot_config('panda', 'axis')).with_task(PANDA_AXIS)
    result = plan(scene)
    assert result.feasible, result.reason
    assert len(result.stats['curve']['frozen_joints']) == 1  # r = 7 - 5 = 2
    tool = scene.robot.tool_frames(result.nominal_path[-1])
    goal = np.asarray(PANDA_AXIS.goal)
    assert np.linalg.norm(tool[:3, 3] - goal[:3]) <= PANDA_AXIS.goal_tolerance
    angle = np.arccos(np.clip(tool[:3, 2] @ goal[3:] / np.linalg.norm(goal[3:]), -1.0, 1.0))
    assert angle <= PANDA_AXIS.orientation_tolerance
    start = scene.robot.tool_frames(result.theta_s)
    assert np.linalg.norm(start[:3, 3] - PANDA_AXIS.start[:3]) <= PANDA_AXIS.goal_tolerance


class _RecordingCurves(CurveSearch):
    """A curve search that keeps each planned curve's criterion and chunk."""

    def __init__(self, *args):
        super().__init__(*args)
        self.planned: list[tuple[int, int]] = []  # (curves examined so far, feasible starts)

    def _plan(self, candidate, search, count):
        self.planned.append((self.examined, count))
        return super()._plan(candidate, search, count)


def _curve_search(scene, seed, cls=CurveSearch, options=None):
    return cls(scene, options or PlannerOptions(), np.random.default_rng(seed),
               lambda line: None, ManifoldCache())


@pytest.mark.parametrize('seed', [0, 7])
def test_a_free_space_position_task_plans_whatever_the_seed(seed):
    """Seeds 0 and 7 said 'no plan on the 6 curves tried' when the clearest samples'
    curves were planned in turn (issue 35)."""
    scene = load_scene(SCENES / 'panda_free_position.yaml')
    result = plan(scene, rng=np.random.default_rng(seed))
    assert result.feasible, result.reason
    assert result.stats['curve']['feasible_starts'] > 0


def test_curves_are_planned_most_feasible_starts_first():
    """Within a chunk, a curve is planned only with starts passing eq. 6, most first."""
    scene = load_scene(SCENES / 'panda_free_position.yaml')
    search = _curve_search(scene, 0, _RecordingCurves)
    result = search.run()
    assert result.feasible, result.reason
    assert search.planned and all(count > 0 for _, count in search.planned)
    for chunk in {examined for examined, _ in search.planned}:
        counts = [count for examined, count in search.planned if examined == chunk]
        assert counts == sorted(counts, reverse=True)
    assert result.stats['curve']['feasible_starts'] == search.planned[-1][1]


class _HopelessCurves(CurveSearch):
    """A curve search on which no start of any slice passes eq. 6."""

    def _examine(self, candidate):
        self.examined_candidates = getattr(self, 'examined_candidates', []) + [candidate]
        return 0, None


def test_no_is_said_only_after_the_whole_budget_of_curves():
    scene = load_scene(SCENES / 'panda_free_position.yaml')
    options = PlannerOptions(curves=30)  # more than one draw of candidates gives (about 20)
    search = _curve_search(scene, 0, _HopelessCurves, options)
    result = search.run()
    assert not result.feasible
    assert len(search.examined_candidates) == 30 == result.stats['curves_examined']
    assert 'no plan on the 30 curves examined' in result.reason
    values = {candidate[1] for candidate in search.examined_candidates}
    assert len(values) == 30  # fresh samples, no curve examined twice


@pytest.mark.parametrize('name', ['ur5e_free_position', 'jaco2_free_position'])
def test_six_joint_arms_plan_position_tasks_tolerating_every_joint(name):
    """Redundancy 3: two joints frozen (the last, which moves the tool point not at all,
    among them), every joint's lock recovered in a drill."""
    scene = load_scene(SCENES / f'{name}.yaml')
    result = plan(scene)
    assert result.feasible, result.reason
    assert result.tolerated_joints == tuple(range(6))
    frozen = result.stats['curve']['frozen_joints']
    assert len(frozen) == 2 and scene.robot.joint_names[5] in frozen
    trials = run_drill(scene, result, 100, np.random.default_rng(5))
    assert all(t.ok for t in trials), [t for t in trials if not t.ok][:1]
