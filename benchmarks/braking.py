"""The cost of certified braking after a lock, and the speed the guarantee allows, per scene.

    .venv/bin/python benchmarks/braking.py [--scenes fig3a panda_shelf ...] [--locks 200]
        [--seed 0] [--max-joint-speed 2.0] [--json OUT.json] [--png OUT.png]

Per scene: the plan (plan time with and without the braking certificate: the time of
`braking_speed_scaling` is measured inside the run), then three timings of the nominal
path as the executor commands it with `--max-joint-speed` (ftplan-bringup's 2 rad/s):
the kinematic one of before issue 36 (every joint at most that speed, no acceleration
limit), TOPP-RA within the robot's limits, and that slowed to the speed whose braking
boxes certify (`stats['max_safe_speed']` is the same at the robot's full limits).
Then `--locks` locks at random moments of the certified command, each followed by the
kinematic sim's braking (simulation/kinematic.py): the smallest clearance during
braking, and the largest distance [rad, ∞-norm] of a braked stop from its lock point
(the deviation from the certified web before the straight move back), against the
certified box. ROS-free; one process.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from ftplan_ros.core import CollisionChecker, load_scene, plan
from ftplan_ros.core.collision.braking import braking_distances, segment_speeds
from ftplan_ros.core.model.motion_limits import robot_motion_limits
from ftplan_ros.core.planning.timing import braking_speed_scaling, slowed, time_within_limits
from ftplan_ros.execution.motion import time_path
from ftplan_ros.simulation.arm import ArmOptions
from ftplan_ros.simulation.kinematic import KinematicArm

SCENES = Path(__file__).resolve().parents[1] / 'config' / 'scenes'
STEP = 0.01  # [s] of the sim


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--scenes', nargs='+',
                        default=['fig3a', 'crowded_sheets_100', 'panda_shelf', 'iiwa_table'])
    parser.add_argument('--locks', type=int, default=200)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--max-joint-speed', type=float, default=2.0)
    parser.add_argument('--json', type=Path, default=None)
    parser.add_argument('--png', type=Path, default=None)
    args = parser.parse_args()
    rows = [measure(name, args) for name in args.scenes]
    for row in rows:
        print(json.dumps(row))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    if args.png:
        draw(rows, args.png)
    return 0


def measure(name: str, args: argparse.Namespace) -> dict:
    """Plan scene `name`, time its nominal path three ways, drill `args.locks` braking locks."""
    scene = load_scene(SCENES / f'{name}.yaml')
    started = time.perf_counter()
    result = plan(scene)
    plan_time = time.perf_counter() - started
    path = np.asarray(result.nominal_path)
    checker = CollisionChecker(scene.robot, scene.obstacles)
    robot_limits = robot_motion_limits(scene.robot)
    limits = robot_limits.scaled(1.0, 1.0)
    limits = type(limits)(np.minimum(limits.velocity, args.max_joint_speed),
                          limits.acceleration, limits.jerk)
    timed = time_within_limits(path, limits)
    started = time.perf_counter()
    speed = braking_speed_scaling(checker, timed, limits.acceleration)
    braking_time = time.perf_counter() - started
    sent = slowed(timed, 1.0 / speed) if 0.0 < speed < 1.0 else timed
    stops = drill(scene, checker, sent, limits, args.locks, np.random.default_rng(args.seed))
    return {'scene': name, 'plan_time_s': plan_time, 'braking_certificate_s': braking_time,
            'max_safe_speed': result.stats['max_safe_speed'], 'executed_speed': speed,
            'kinematic_s': float(time_path(path, args.max_joint_speed)[-1]),
            'within_limits_s': float(timed.times[-1]), 'certified_braking_s':
            float(sent.times[-1]), **stops}


def drill(scene, checker, sent, limits, locks: int, rng) -> dict:
    """Lock a random joint at random moments of `sent`; brake in the kinematic sim."""
    smallest, farthest, outside = np.inf, 0.0, 0
    speeds = segment_speeds(sent.positions, sent.velocities, sent.times)
    reach = braking_distances(speeds, limits.acceleration)
    for _ in range(locks):
        arm = KinematicArm(scene.robot, sent.positions[0], ArmOptions(max_joint_speed=1e3))
        arm.follow(sent.positions[1:], sent.times[1:], 0, 0)
        moment = rng.uniform(0.0, sent.times[-1])
        while arm.time + STEP < moment:
            arm.step(STEP)
        arm.step(moment - arm.time)
        lock_at = arm.q.copy()
        arm.lock(int(rng.integers(len(lock_at))), None, 0)
        swept = [lock_at[None, :]]
        while arm.moving:
            swept.append(arm.step(STEP).swept)
        swept = np.vstack([s for s in swept if s is not None])
        smallest = min(smallest, float(checker.min_clearance(swept).min()))
        gap = np.abs(arm.q - lock_at)
        farthest = max(farthest, float(gap.max()))
        k = min(int(np.searchsorted(sent.times, moment)), len(reach)) - 1
        outside += bool(np.any(gap > reach[max(k, 0)] + 1e-9))
    return {'locks': locks, 'min_braking_clearance_m': smallest,
            'max_braking_deviation_rad': farthest, 'stops_outside_box': outside}


def draw(rows: list[dict], png: Path) -> None:
    """Two panels: executed duration three ways, and the speed the guarantee allows."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    names = [row['scene'] for row in rows]
    x = np.arange(len(rows))
    figure, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    for k, (key, label) in enumerate([('kinematic_s', 'kinematic (before)'),
                                      ('within_limits_s', 'TOPP-RA within limits'),
                                      ('certified_braking_s', 'certified braking')]):
        left.bar(x + (k - 1) * 0.27, [row[key] for row in rows], 0.27, label=label)
    left.set_xticks(x, names, rotation=15)
    left.set_ylabel('nominal path duration [s]')
    left.legend()
    right.bar(x, [row['max_safe_speed'] for row in rows], 0.5)
    right.set_xticks(x, names, rotation=15)
    right.set_ylabel('max_safe_speed (of the full limits)')
    right.set_ylim(0.0, 1.05)
    figure.tight_layout()
    figure.savefig(png, dpi=120)


if __name__ == '__main__':
    raise SystemExit(main())
