"""The `ftplan` command: plan, drill, draw, benchmark and study failure-tolerant motions.

    ftplan plan SCENE.yaml [--json OUT.json] [--png FIG.png] [--seed S] [--margin M]
    ftplan drill SCENE.yaml [--trials N] [--seed S] [--png MOTION.png] [--json OUT.json]
    ftplan figure SCENE.yaml [--out DIR]
    ftplan bench [--robot planar3r|panda|iiwa14] [--scenes N] [--seed S] [--cells C]
                 [--crowded-cells C] [--grid-baseline N]
                 [--json OUT.json]
    ftplan study SPEC.yaml --out DIR [--scheduler ADDRESS] [--workers N]
    ftplan replay RECORDING.mcap [--png MOTION.png] [--scene SCENE.yaml]

Exit codes: 0 done (for `plan`: a failure-tolerant plan exists), 1 no failure-tolerant
plan (or a drill trial failed, or a recording without a run to draw), 2 bad input (one
line on stderr naming the field; a file that is not a complete recording too).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

import numpy as np

from .core import (
    InputError,
    PlannerOptions,
    VerificationOptions,
    load_kernels,
    load_scene,
    plan,
)
from .core.model.task_space import describe_point
from .core.planning.drill import drill_json, drilled_motion, run_drill, summarize_drill
from .progress import Progress

log = logging.getLogger('ftplan')


def main(argv: list[str] | None = None) -> int:
    """Run the `ftplan` command line; return the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format='%(levelname)s %(name)s: %(message)s')
    try:
        return args.run(args)
    except InputError as error:
        print(f'ftplan: error: {error}', file=sys.stderr)
        return 2
    except OSError as error:
        print(f'ftplan: error: {error.filename or ""}: {error.strerror}', file=sys.stderr)
        return 2


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog='ftplan', description=__doc__.splitlines()[0])
    parser.add_argument('-v', '--verbose', action='store_true', help='log what the core does')
    commands = parser.add_subparsers(required=True, metavar='COMMAND')

    planning = commands.add_parser('plan', help='plan the scene\'s task')
    planning.add_argument('scene', type=Path, help='scene YAML (robot, obstacles, task)')
    planning.add_argument('--json', type=Path, help='write the plan result JSON here')
    planning.add_argument('--png', type=Path, help='write a figure of the plan here')
    _planner_arguments(planning)
    planning.set_defaults(run=_plan_command)

    drill = commands.add_parser('drill', help='Monte Carlo failure drill of the plan')
    drill.add_argument('scene', type=Path)
    drill.add_argument('--trials', type=int, default=1000, help='failures to try (1000)')
    drill.add_argument('--png', type=Path, help='draw one drilled motion here')
    drill.add_argument('--json', type=Path, help='write every trial (its whole motion) here')
    _planner_arguments(drill)
    drill.set_defaults(run=_drill_command)

    figure = commands.add_parser('figure', help='draw the paper\'s Fig. 3 and Fig. 4 for a scene')
    figure.add_argument('scene', type=Path)
    figure.add_argument('--out', type=Path, default=Path('out'), help='folder (out/)')
    _planner_arguments(figure)
    figure.set_defaults(run=_figure_command)

    _add_bench_command(commands)
    _add_study_command(commands)
    _add_replay_command(commands)
    return parser


def _add_bench_command(commands) -> None:
    """Add `ftplan bench`: the planner timed against a baseline in one run."""
    bench = commands.add_parser('bench', help='time the planner against a baseline in one run')
    bench.add_argument('--robot', default='planar3r', choices=('planar3r', 'panda', 'iiwa14'),
                       help='planar3r (the paper\'s arm, recall against a reference grid) or a '
                       '7-joint arm (pose tasks among 10 obstacles, against sampled locks); '
                       'planar3r')
    bench.add_argument('--scenes', type=int, default=30,
                       help='random scenes per group (30; a 7-joint arm: tasks, 30)')
    bench.add_argument('--seed', type=int, default=0)
    bench.add_argument('--cells', type=int,
                       help='planar3r: cells per joint of the reference grid that decides '
                       'whether a plan exists (256: 1.4 deg; 16 to 256)')
    bench.add_argument('--crowded-cells', type=int,
                       help='planar3r: cells per joint of the grid that keeps a plan in the '
                       'crowded scenes as they are built (128)')
    bench.add_argument('--grid-baseline', type=int, metavar='N',
                       help='planar3r: also time the exhaustive grid planner on N^3 cell '
                       'centres (180: 2 deg; 16 to 256; 0, the default: not run)')
    bench.add_argument('--json', type=Path, help='write every measurement here')
    bench.set_defaults(run=_bench_command)


def _add_study_command(commands) -> None:
    """Add `ftplan study`: a map or sweep of many tasks on Dask."""
    study = commands.add_parser('study', help='plan a map or a sweep of many tasks on Dask')
    study.add_argument('spec', type=Path, help='study spec YAML (scene, vary, planner, chunk)')
    study.add_argument('--out', type=Path, required=True,
                       help='folder for the results (Parquet) and figures; rerun to resume')
    study.add_argument('--scheduler', help='address of a running Dask scheduler, e.g. '
                       'tcp://HOST:8786 (default: a local cluster)')
    study.add_argument('--workers', type=int,
                       help='worker processes of the local cluster (default: one per CPU)')
    study.set_defaults(run=_study_command)


def _add_replay_command(commands) -> None:
    """Add `ftplan replay`: the summary and figure of a bringup recording."""
    replay = commands.add_parser('replay', help='summarise a recording of ftplan-bringup '
                                 '(as ros2 bag info does) and draw its run')
    replay.add_argument('recording', type=Path, help='an MCAP file of ftplan-bringup --record')
    replay.add_argument('--png', type=Path, help='draw the recorded run here, as the '
                        'bringup\'s --png draws it live')
    replay.add_argument('--scene', type=Path, help='the scene of the run (default: the scene '
                        'file the recording names)')
    replay.set_defaults(run=_replay_command)


def _planner_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument('--seed', type=int, default=0, help='seed of the random generators (0)')
    parser.add_argument('--margin', type=float, default=0.0,
                        help='clearance [m] the guarantee keeps from obstacles (0.0)')


def _at_least(value: int, least: int, flag: str, most: int = 2 ** 62) -> None:
    if not least <= value <= most:
        raise InputError(flag, f'must be at least {least}, got {value}' if value < least
                         else f'must be at most {most}, got {value}')


def _plan(args: argparse.Namespace, progress: Progress):
    """Check the flags (before any work), load the scene and plan it."""
    _check_png(getattr(args, 'png', None))
    _at_least(args.seed, 0, '--seed')
    scene = load_scene(args.scene)
    if not np.isfinite(args.margin) or args.margin < 0:
        raise InputError('--margin', f'must be a finite clearance >= 0, got {args.margin}')
    options = PlannerOptions(verification=VerificationOptions(margin=args.margin))
    load_kernels(scene.robot)  # not part of the plan time
    result = plan(scene, options, np.random.default_rng(args.seed), progress=progress.line)
    return scene, result


def _plan_command(args: argparse.Namespace) -> int:
    progress = Progress()
    scene, result = _plan(args, progress)
    print(_describe(scene, result))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result.to_json(), indent=1, allow_nan=False))
        print(f'wrote {args.json}')
    if args.png:
        from .figures import plan_figure, save_figure
        print(f'wrote {save_figure(plan_figure(scene, result), args.png)}')
    return 0 if result.feasible else 1


def _drill_command(args: argparse.Namespace) -> int:
    _at_least(args.trials, 1, '--trials', 10_000_000)
    progress = Progress()
    scene, result = _plan(args, progress)
    print(_describe(scene, result))
    if not result.feasible:
        return 1
    progress.line(f'drilling {args.trials} locked-joint failures')
    trials = run_drill(scene, result, args.trials, np.random.default_rng(args.seed),
                       progress=progress.count)
    print(summarize_drill(trials, scene.robot.joint_names))
    failed = [t for t in trials if not t.ok]
    print(f'{len(trials) - len(failed)}/{len(trials)} trials reached the goal without collision')
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(drill_json(trials, scene.robot.joint_names),
                                        allow_nan=False))
        print(f'wrote {args.json}')
    if args.png:
        from .figures import motion_figure, save_figure
        drawn = _trial_to_draw(result, trials)
        if drawn is None:
            print(f'ftplan: no drilled motion to draw in {args.png}', file=sys.stderr)
            return 1
        (motion, lock_index, _), worst = drawn
        what = 'a failed trial' if not worst.ok else \
            f'the drill\'s closest call, {worst.min_clearance:.3f} m'
        title = (f'{scene.robot.joint_names[worst.joint]} locked at {worst.progress:.0%} of '
                 f'the path ({what})')
        figure = motion_figure(scene, motion, lock_index, worst.joint, title)
        print(f'wrote {save_figure(figure, args.png)}')
    return 0 if not failed else 1


def _trial_to_draw(result, trials):
    """Return (drilled motion, trial): a failed trial's that can be drawn, else the closest call."""
    failed = [t for t in trials if not t.ok]
    recovered = sorted((t for t in trials if t.ok), key=lambda t: t.min_clearance)
    for trial in failed + recovered:
        motion = drilled_motion(result, trial.joint, trial.progress)
        if motion is not None:
            return motion, trial
    return None


def _figure_command(args: argparse.Namespace) -> int:
    from .figures import joint_space_figure, save_figure, workspace_figure
    progress = Progress()
    scene, result = _plan(args, progress)
    print(_describe(scene, result))
    stem = args.scene.stem
    progress.line('drawing')
    for name, figure in ((f'{stem}_workspace.png', workspace_figure(scene, result)),
                         (f'{stem}_joint_space.png', joint_space_figure(scene, result))):
        print(f'wrote {save_figure(figure, args.out / name)}')
    return 0


_PLANAR_BENCH_FLAGS = {'cells': 256, 'crowded_cells': 128, 'grid_baseline': 0}  # defaults


def _bench_command(args: argparse.Namespace) -> int:
    _at_least(args.scenes, 1, '--scenes', 100_000)
    _at_least(args.seed, 0, '--seed')
    if args.robot != 'planar3r':
        for flag in _PLANAR_BENCH_FLAGS:
            if getattr(args, flag) is not None:
                raise InputError(f'--{flag.replace("_", "-")}', f'sets the planar3r '
                                 f'benchmark; --robot {args.robot} has no grid')
        from .bench.spatial import run_spatial_benchmark
        return run_spatial_benchmark(args.robot, args.scenes, args.seed, args.json, Progress())
    cells, crowded_cells, grid_baseline = (
        _PLANAR_BENCH_FLAGS[flag] if getattr(args, flag) is None else getattr(args, flag)
        for flag in _PLANAR_BENCH_FLAGS)
    _at_least(cells, 16, '--cells', 256)  # 256^3 cells: about 2 GB at the grid's peak
    _at_least(crowded_cells, 16, '--crowded-cells', 256)
    if grid_baseline:
        _at_least(grid_baseline, 16, '--grid-baseline', 256)
    from .bench.recall import run_recall_benchmark
    return run_recall_benchmark(args.scenes, args.seed, cells, crowded_cells, args.json,
                                Progress(), grid_baseline)


def _study_command(args: argparse.Namespace) -> int:
    from .study.command import run_study_command  # Dask loads for studies only
    return run_study_command(args.spec, args.out, args.scheduler, args.workers, Progress())


def _check_png(png: Path | None) -> None:
    """Raise InputError unless `png` (a --png flag's path) is None or ends in .png."""
    if png is not None and png.suffix.lower() != '.png':
        raise InputError('--png', f'figures are PNG files: give a path ending in .png, not {png}')


def _replay_command(args: argparse.Namespace) -> int:
    _check_png(args.png)
    from .recording.bag_reader import open_bag  # ROS message readers load for replays only
    from .recording.replay import describe_run, draw_recorded_run, recorded_runs, recorded_scene
    with open_bag(args.recording) as bag:
        print(bag.info())
        if args.png is None:
            return 0
        scene = recorded_scene(bag, args.scene)
        runs = recorded_runs(bag, list(scene.robot.joint_names))
    print('\n'.join(describe_run(run) for run in runs) or 'no recorded run')
    drawn = draw_recorded_run(scene, runs, args.png)
    if drawn is None:
        print(f'ftplan: no recorded run to draw in {args.png}', file=sys.stderr)
        return 1
    print(f'wrote {args.png} (run {drawn.run})')
    return 0


def _describe(scene, result) -> str:
    """Describe the outcome in a few lines: θ_s and hits in degrees, time and checks."""
    stats = result.stats
    task, names = scene.task, scene.robot.joint_names
    lines = [f'scene {scene.name}: {task.kind} task {describe_point(task.kind, task.start)} -> '
             f'{describe_point(task.kind, task.goal)} m, {len(scene.obstacles)} obstacles']
    if not result.feasible:
        lines.append(f'no failure-tolerant plan: {result.reason}')
    else:
        degrees = np.degrees
        lines.append(f'feasible: theta_s = {_deg(degrees(result.theta_s))} deg, tolerating '
                     f'{_joint_list(names, result.tolerated_joints)}')
        if 'curve' in stats:
            curve = stats['curve']
            lines.append(f'  curve on the self-motion manifolds: '
                         f'{", ".join(curve["frozen_joints"])} frozen at '
                         f'{_deg(degrees(curve["frozen_values_rad"]))} deg')
        for joint, hit in zip(result.tolerated_joints, result.failure_plane_hits, strict=True):
            lines.append(f'  H{joint + 1} ({names[joint]}) hit on M_g^F: '
                         f'{_deg(degrees(hit))} deg')
        lines.append(f'  S_F: {result.surface.paths.shape[0]} paths x '
                     f'{result.surface.paths.shape[1]} waypoints, smallest clearance sampled '
                     f'{stats["min_clearance_m"]:.3f} m ({stats["criterion"]})')
    line = f'plan time {stats["plan_time_s"]:.3f} s, method {stats.get("method", "?")}, ' \
        f'{stats.get("collision_checks", 0)} clearance queries'
    if 'start_candidates' in stats:
        line += f', {stats.get("theta_S", 0)} of {stats["start_candidates"]} obstacle-free ' \
            'starts pass eq. (6)'
    elif 'grid_cells' in stats:
        line += f', failure-tolerant set on a {stats["grid_cells"]}^3 joint grid'
        if stats.get('classified_cells', stats['grid_cells']) != stats['grid_cells']:
            line += f' pooled from {stats["classified_cells"]}^3'
    lines.append(line)
    return '\n'.join(lines)


def _joint_list(names, joints) -> str:
    return 'every joint' if len(joints) == len(names) else ', '.join(names[j] for j in joints)


def _deg(values: np.ndarray) -> str:
    return '[' + ', '.join(f'{v:.1f}' for v in values) + ']'


if __name__ == '__main__':
    sys.exit(main())
