"""Benchmark for 7-joint arms: the planner against what a user would otherwise script.

Seeded random pose tasks for the Panda or the iiwa among 10 random obstacles (spheres,
boxes, cylinders clear of the arm at both ends of the task), tolerating every joint but
the elbow (whose lock no pose task on these arms survives: see the README). For each
task, in the same run:

* the planner, cold (no traced manifolds kept between tasks), timed for its answer alone
  (`coverage_attempts=0`: on a "no" it does not go on to plan for fewer joints, which
  reports the set a plan covers but proves nothing about this task), and, when it finds
  a plan, a 50-trial drill of it (dense sampling, core/planning/drill.py) as the referee;
* the baseline: for each of up to 8 collision-free inverse-kinematics solutions of the
  start (clearest first), the goal solution nearest it, a joint path between them
  (straight, or OMPL's RRT-Connect when that collides; checked by sampling), then at 8
  moments along it and for every tolerated joint locked there, inverse kinematics of
  the goal in the failure plane and a straight or RRT-Connect path to it (0.2 s budget
  each). It answers "yes" as soon as one start's sampled locks all recover: a sampled
  check, not a guarantee.

Times are ratios and percentiles within this run.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ompl_util

from ..core import CollisionChecker, Obstacle, PlannerOptions, Scene, Task, parse_scene, plan
from ..core.model.paths import densify, point_at_fraction
from ..core.paper.manifolds import project_many
from ..core.planning.drill import run_drill

ROBOTS = {'panda': ('panda.yaml', 'panda_joint4'), 'iiwa14': ('iiwa14.yaml', 'iiwa_joint_4')}
CONFIG = Path(__file__).resolve().parents[3] / 'config' / 'robots'
OBSTACLES = 10
LOCK_MOMENTS = 8
RRT_BUDGET = 0.2  # [s] per failure-plane search
SAMPLE_STEP = 0.01  # [rad] the baseline's collision samples along a path
DRILL_TRIALS = 50
ANSWER_ALONE = PlannerOptions(coverage_attempts=0)


@dataclass(frozen=True)
class TaskRun:
    """One task's answers and times [s]."""

    planner_feasible: bool
    planner_s: float
    drill_reached: int       # of DRILL_TRIALS, when the planner found a plan
    baseline_feasible: bool
    baseline_s: float
    baseline_reason: str
    reason: str


def random_task(robot_name: str, rng: np.random.Generator) -> Scene:
    """Make a pose task among random obstacles for the named arm (see the module docstring)."""
    file, elbow = ROBOTS[robot_name]
    scene = parse_scene({'robot': file}, directory=CONFIG)
    robot = scene.robot
    tolerate = [name for name in robot.joint_names if name != elbow]
    free = CollisionChecker(robot, [])
    limits = robot.limits
    while True:
        q1 = rng.uniform(limits[:, 0], limits[:, 1])
        q2 = np.clip(q1 + rng.normal(0.0, 0.5, robot.n_joints), limits[:, 0], limits[:, 1])
        ends = np.stack([q1, q2])
        if free.min_clearance(ends, 0.0).min() > 0.0:
            break
    task = Task(tuple(robot.forward_kinematics(q1)), tuple(robot.forward_kinematics(q2)),
                0.005, 0.01)
    obstacles: list[Obstacle] = []
    while len(obstacles) < OBSTACLES:
        candidate = _random_obstacle(rng)
        checker = CollisionChecker(robot, [candidate])
        against_obstacle = checker.channel_links[:, 1] < 0
        clear = checker.clearance(ends, 0.05)[:, against_obstacle].min() > 0.05
        if clear and checker.base_clearance()[0] > 0.05:
            obstacles.append(candidate)
    return scene.with_obstacles(obstacles).with_task(task).with_tolerated(tolerate)


def _random_obstacle(rng: np.random.Generator) -> Obstacle:
    centre = tuple(float(v) for v in rng.uniform([0.1, -0.6, 0.0], [0.8, 0.6, 0.9]))
    rpy = tuple(float(v) for v in rng.uniform(-np.pi, np.pi, 3))
    kind = rng.choice(['sphere', 'box', 'cylinder'])
    if kind == 'sphere':
        return Obstacle('sphere', centre, radius=float(rng.uniform(0.05, 0.12)))
    if kind == 'box':
        return Obstacle('box', centre, size=tuple(float(v) for v in rng.uniform(0.05, 0.25, 3)),
                        rpy=rpy)
    return Obstacle('cylinder', centre, radius=float(rng.uniform(0.03, 0.1)),
                    length=float(rng.uniform(0.1, 0.4)), rpy=rpy)


def run_task(scene: Scene, seed: int) -> TaskRun:
    """Plan the task cold, drill a plan found, and run the baseline on it."""
    started = time.perf_counter()
    result = plan(scene, ANSWER_ALONE, rng=np.random.default_rng(seed))
    planner_s = time.perf_counter() - started
    reached = 0
    if result.feasible:
        trials = run_drill(scene, result, DRILL_TRIALS, np.random.default_rng(seed))
        reached = sum(t.ok for t in trials)
    started = time.perf_counter()
    baseline = SampledLockBaseline(scene, np.random.default_rng(seed))
    ok, why = baseline.run()
    return TaskRun(result.feasible, planner_s, reached, ok, time.perf_counter() - started, why,
                   result.reason)


class SampledLockBaseline:
    """The script a user would write without ftplan (see the module docstring)."""

    def __init__(self, scene: Scene, rng: np.random.Generator):
        self.scene = scene
        self.robot = scene.robot
        self.rng = rng
        self.checker = CollisionChecker(scene.robot, scene.obstacles)

    def run(self, starts: int = 8) -> tuple[bool, str]:
        """Return whether some start's sampled locks all recover, and why not."""
        task = self.scene.task
        why = 'no collision-free inverse kinematics of the start'
        for start in self._solutions(np.asarray(task.start))[:starts]:
            goal = self._clear_solution(np.asarray(task.goal), near=start)
            path = None if goal is None else self._joint_path(start, goal, None)
            if path is None:
                why = 'no collision-free joint path from a start to the goal'
                continue
            why = self._unrecovered_lock(path)
            if not why:
                return True, ''
        return False, why

    def _unrecovered_lock(self, path: np.ndarray) -> str:
        """Say which sampled lock along the path does not recover, or ''."""
        for fraction in np.linspace(0.0, 1.0, LOCK_MOMENTS):
            theta = point_at_fraction(path, fraction)
            for joint in self.scene.tolerated_joints:
                if not self._recovers(theta, joint):
                    return (f'no recovery with {self.robot.joint_names[joint]} locked at '
                            f'{fraction:.0%} of the path')
        return ''

    def _solutions(self, x: np.ndarray) -> np.ndarray:
        """Collision-free inverse-kinematics solutions (k, n) of x, clearest first."""
        limits = self.robot.limits
        seeds = self.rng.uniform(limits[:, 0], limits[:, 1], size=(64, self.robot.n_joints))
        solved, converged = project_many(self.robot, x, seeds)
        solved = solved[converged]
        clearance = self.checker.min_clearance(solved, 0.05)
        order = np.argsort(-clearance)
        return solved[order][clearance[order] > 0.0]

    def _clear_solution(self, x: np.ndarray, near: np.ndarray,
                        fixed: int | None = None) -> np.ndarray | None:
        """Return the collision-free inverse-kinematics solution nearest `near`, or None.

        `fixed` keeps a joint at its value in `near`.
        """
        limits = self.robot.limits
        seeds = self.rng.uniform(limits[:, 0], limits[:, 1], size=(32, self.robot.n_joints))
        seeds[0] = near
        if fixed is not None:
            seeds[:, fixed] = near[fixed]
        solved, converged = project_many(self.robot, x, seeds, fixed_joint=fixed)
        solved = solved[converged]
        solved = solved[self.checker.min_clearance(solved, 0.0) > 0.0]
        if len(solved) == 0:
            return None
        return solved[int(np.argmin(np.linalg.norm(solved - near, axis=1)))]

    def _free(self, path: np.ndarray) -> bool:
        return bool(self.checker.min_clearance(densify(path, SAMPLE_STEP), 0.0).min() > 0.0)

    def _recovers(self, theta: np.ndarray, joint: int) -> bool:
        goal = self._clear_solution(np.asarray(self.scene.task.goal), theta, joint)
        return goal is not None and self._joint_path(theta, goal, joint) is not None

    def _joint_path(self, start: np.ndarray, goal: np.ndarray, locked: int | None,
                    ) -> np.ndarray | None:
        """Find a collision-free path (k, n) start to goal, `locked` held: straight or RRT."""
        straight = np.stack([start, goal])
        if self._free(straight):
            return straight
        return self._rrt_connect(start, goal, locked)

    def _rrt_connect(self, start: np.ndarray, goal: np.ndarray, locked: int | None,
                     ) -> np.ndarray | None:
        """OMPL's RRT-Connect over the joints but `locked`, within the joint limits."""
        free = [j for j in range(self.robot.n_joints) if j != locked]
        space = ob.RealVectorStateSpace(len(free))
        bounds = ob.RealVectorBounds(len(free))
        for k, j in enumerate(free):
            bounds.setLow(k, float(self.robot.limits[j, 0]))
            bounds.setHigh(k, float(self.robot.limits[j, 1]))
        space.setBounds(bounds)
        setup = og.SimpleSetup(space)
        whole = start.copy()

        def valid(state) -> bool:
            whole[free] = [state[k] for k in range(len(free))]
            return bool(self.checker.min_clearance(whole[None, :], 0.0)[0] > 0.0)

        setup.setStateValidityChecker(valid)
        setup.getSpaceInformation().setStateValidityCheckingResolution(0.005)
        ends = [space.allocState(), space.allocState()]
        for state, values in zip(ends, (start, goal), strict=True):
            for k, j in enumerate(free):
                state[k] = float(values[j])
        setup.setStartAndGoalStates(*ends)
        setup.setPlanner(og.RRTConnect(setup.getSpaceInformation()))
        if not (setup.solve(RRT_BUDGET) and setup.haveExactSolutionPath()):
            return None
        solution = setup.getSolutionPath()
        path = np.tile(start, (solution.getStateCount(), 1))
        for row in range(len(path)):
            path[row, free] = [solution.getState(row)[k] for k in range(len(free))]
        return path


def run_spatial_benchmark(robot_name: str, tasks: int, seed: int, json_path: Path | None,
                          progress) -> int:
    """Run `tasks` random tasks; print the table; 1 if a plan found failed its drill."""
    ompl_util.setLogLevel(ompl_util.LogLevel.LOG_WARN)
    rng = np.random.default_rng(seed)
    runs = []
    for k in range(tasks):
        runs.append(run_task(random_task(robot_name, rng), seed + k))
        progress.count(k + 1, tasks, 'tasks')
    print(summarize(robot_name, runs))
    if json_path is not None:
        json_path.parent.mkdir(parents=True, exist_ok=True)
        json_path.write_text(json.dumps([asdict(run) for run in runs], indent=1))
    return 1 if any(r.planner_feasible and r.drill_reached < DRILL_TRIALS for r in runs) else 0


def summarize(robot_name: str, runs: list[TaskRun]) -> str:
    """Tabulate rates, p50/p95 times and how the answers compare."""
    planner = np.array([r.planner_s for r in runs]) * 1e3
    baseline = np.array([r.baseline_s for r in runs]) * 1e3
    planned = [r for r in runs if r.planner_feasible]
    agree = sum(r.planner_feasible == r.baseline_feasible for r in runs)
    lines = [
        f'{robot_name}: {len(runs)} random pose tasks among {OBSTACLES} obstacles, every joint '
        'but the elbow tolerated',
        f'{"":<30}{"yes":>6}{"p50 [ms]":>10}{"p95 [ms]":>10}',
        f'{"planner (cold, certified)":<30}{len(planned):>6}{_p(planner, 50):>10}'
        f'{_p(planner, 95):>10}',
        f'{"baseline (sampled locks)":<30}{sum(r.baseline_feasible for r in runs):>6}'
        f'{_p(baseline, 50):>10}{_p(baseline, 95):>10}',
        f'answers agree on {agree}/{len(runs)}; planner yes, baseline no: '
        f'{sum(r.planner_feasible and not r.baseline_feasible for r in runs)}; baseline yes, '
        f'planner no: {sum(r.baseline_feasible and not r.planner_feasible for r in runs)}',
        f'plans whose {DRILL_TRIALS}-trial drill failed: '
        f'{sum(r.drill_reached < DRILL_TRIALS for r in planned)} (must be 0)',
    ]
    return '\n'.join(lines)


def _p(values: np.ndarray, q: int) -> str:
    return f'{np.percentile(values, q):.0f}' if len(values) else '-'
