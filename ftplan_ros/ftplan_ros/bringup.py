"""`ftplan-bringup`: the whole node suite in one process, planning and drilling a scene.

    ftplan-bringup --scene config/scenes/fig3a.yaml --drill joint2@0.4
    ftplan-bringup --scene config/scenes/fig3a.yaml --trials 20 --seed 1 --png out/motion.png
    ftplan-bringup --scene config/scenes/fig3a.yaml --drill joint2@0.4 --record out/run.mcap

The planner, executor, sim and injector nodes run on one MultiThreadedExecutor in a
background thread (no launch system needed); a small director, a PlanClient, plans the
scene's task and then, for each run, resets the sim, executes the plan and lets the
injector lock a joint: first one run per `--drill JOINT@FRACTION` (or JOINT@SECONDSs),
then `--trials N` runs with a random joint at a random moment (seed `--seed`); with
neither, one run without a failure. It prints a summary (plan time, the joint and moment
of each failure, asked and landed, recovery time, goal errors in position [m] and, for
axis and pose tasks, orientation [rad], minimum clearance; how many runs were drilled as
asked) and exits 0 only when every run reached the goal without a collision and every
drill was drilled as asked (its lock landed on the nominal path within 0.02 of its
fraction: `Drill.missed`), 1 otherwise, 2 on bad input and 130 on Ctrl-C (after shutting
every node down). `--record FILE.mcap` writes every topic of the run to a rosbag2-compatible
MCAP file (nodes/recorder.py), closed on Ctrl-C too; `ftplan replay` reads it back.
"""

from __future__ import annotations

import argparse
import shlex
import signal
import sys
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import rclpy
from rclpy.context import Context
from rclpy.logging import LoggingSeverity
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import JointState

from ftplan_msgs_py import DiagnosticReading, read_joint_state

from .core import InputError, Scene, check_plannable, load_scene
from .core.model.task_space import describe_point
from .nodes.executor import ExecutorNode
from .nodes.injector import InjectorNode, parse_drill
from .nodes.planner import PlannerNode
from .nodes.recorder import Recording
from .nodes.reporting import parse_number, parse_vector
from .nodes.sim import SIM_BACKENDS, SimNode
from .nodes.spinning import BackgroundSpin, RclError
from .nodes.topics import (
    EXECUTOR_NODE,
    INJECTOR_NODE,
    JOINT_STATES,
    PLANNER_NODE,
    SIM_NODE,
)
from .plan_client import Outcome, PlanClient, PlannedMotion
from .progress import Progress
from .recording.bag_writer import BagWriter

SIM_STATUS = f'{SIM_NODE}: arm'
# The executor's tolerances for an arm under physics (--sim mujoco) [rad]: it stops
# near its path, not on it, and settles asymptotically (README, "Physics").
PHYSICS_TOLERANCES = {'arrival_tolerance': 1e-3, 'max_path_offset': 0.02,
                      'stopped_tolerance': 1e-6}
# The clearance [m] the plan, and the executor's own certifications, keep for an arm
# under physics: its servos put a joint or the tool up to 4.2 mm from where commanded
# (panda_shelf), and the plans of the kinematic guarantee pass obstacles 0.2 mm apart
# (README, "Tracking error and clearance").
PHYSICS_MARGIN = 0.005
INJECTOR_STATUS = f'{INJECTOR_NODE}: drills'
# How long [s] a run waits, after the executor is done, for the sim's arm to stand (at
# the goal, if it succeeded): under physics the arm settles on after the executor's
# arrival tolerance, and the sim judges the goal again each second while it stands.
SETTLE_TIMEOUT = 10.0


@dataclass(frozen=True)
class RunReport:
    """What happened in one run (angles [rad], distances [m], times [s])."""

    run: int
    drill: str                 # the drill armed for the run ('' for none)
    ok: bool                   # reached the goal without a collision
    message: str
    locked_joint: str = ''
    lock_progress: float = float('nan')    # fraction of the nominal path where it locked
    recovery_time: float = float('nan')    # lock event -> goal
    goal_error: float = float('nan')
    goal_orientation_error: float = float('nan')
    min_clearance: float = float('nan')
    collisions: int = 0
    lock_configuration: np.ndarray | None = None   # (n,) where the arm stopped, locked
    motion: np.ndarray | None = None               # (k, n) recorded joint states
    missed: str = ''           # how the lock missed the drill ('' drilled as asked, or none)
    contacts: int = 0          # MuJoCo's contacts (--sim mujoco)
    tracking_error: float = float('nan')   # largest |q - commanded| of a joint (mujoco)
    tracking_displacement: float = float('nan')  # farthest a joint or the tool was from
    #                                              its commanded place [m] (mujoco)
    standstill_time: float = float('nan')  # lock -> the arm stands (mujoco)
    braking_clearance: float = float('nan')  # smallest from the lock to the stop after it
    braking_deviation: float = float('nan')  # ∞-norm of the stop from the lock point


class Suite:
    """The four nodes on one MultiThreadedExecutor, spinning in a background thread."""

    def __init__(self, scene_file: str, *, speed: float = 2.0, rate: float = 100.0,
                 sim: str = 'kinematic', drills: Sequence[str] = (), random_drills: int = 0,
                 seed: int = 0,
                 context: Context | None = None, log_level: LoggingSeverity | None = None):
        if log_level is not None:
            for name in (PLANNER_NODE, EXECUTOR_NODE, SIM_NODE, INJECTOR_NODE):
                rclpy.logging.set_logger_level(name, log_level)
        common = [Parameter('scene_file', value=str(scene_file))]
        self.planner = PlannerNode(context=context, parameter_overrides=common + [
            Parameter('max_joint_speed', value=float(speed))] + (
                [Parameter('margin', value=PHYSICS_MARGIN)] if sim == 'mujoco' else []))
        self.executor_node = ExecutorNode(context=context, parameter_overrides=common + [
            Parameter('max_joint_speed', value=float(speed))] + (
                [Parameter(name, value=value) for name, value in PHYSICS_TOLERANCES.items()]
                + [Parameter('margin', value=PHYSICS_MARGIN)] if sim == 'mujoco' else []))
        self.sim = SimNode(context=context, parameter_overrides=common + [
            Parameter('max_joint_speed', value=2.0 * float(speed)),
            Parameter('rate', value=float(rate)), Parameter('sim_backend', value=sim)])
        injector_parameters = common + [Parameter('random_drills', value=int(random_drills)),
                                        Parameter('seed', value=int(seed))]
        if drills:
            injector_parameters.append(Parameter('drills', value=list(drills)))
        self.injector = InjectorNode(context=context, parameter_overrides=injector_parameters)
        self.spin = BackgroundSpin([self.planner, self.executor_node, self.sim, self.injector],
                                   context=context, name='ftplan-suite')

    def shutdown(self) -> None:
        """Stop spinning and destroy every node."""
        self.spin.stop()


class Director:
    """Plan once, then run executions with drills, one after the other, through ROS."""

    def __init__(self, client: PlanClient, scene: Scene, progress: Progress | None = None):
        self.client = client
        self.scene = scene
        self.progress = progress or Progress(quiet=True)
        self.motion: PlannedMotion | None = None
        self.recording: list[np.ndarray] = []
        self._record = False
        # The drill armed for each execution, as the injector says it: kept here, as it
        # comes, because a long run's statuses overflow the client's bounded log (an
        # executor at 10 Hz for 50 s), and the run read as one without a drill.
        self.drills: dict[str, str] = {}
        names = list(scene.robot.joint_names)
        client.create_subscription(JointState, JOINT_STATES,
                                   lambda msg: self._joint_state(msg, names), 100)
        client.add_status_listener(self._injector_status)

    def _joint_state(self, msg: JointState, names: list[str]) -> None:
        if self._record:
            try:
                self.recording.append(read_joint_state(msg, names))
            except ValueError:
                pass

    def _injector_status(self, reading: DiagnosticReading) -> None:
        execution = reading.values.get('execution')
        if reading.name == INJECTOR_STATUS and execution and 'drill' in reading.values:
            self.drills[execution] = reading.values['drill']

    def plan(self, timeout: float = 60.0) -> PlannedMotion:
        """Plan the scene's task; a failed plan names the planner's reason."""
        task = self.scene.task
        if task is None:
            raise InputError('task', f'scene {self.scene.name} has no task to plan')
        if not self.client.wait_until_ready(timeout=10.0):
            return PlannedMotion(Outcome.UNAVAILABLE, 'the planner or executor did not start')
        self.progress.line(f'planning {self.scene.name}: {describe_point(task.kind, task.start)}'
                           f' -> {describe_point(task.kind, task.goal)} m')
        self.motion = self.client.plan(goal=task.goal, start=task.start,
                                       frame_id=self.scene.frame_id, timeout=timeout)
        return self.motion

    def run(self, number: int, record: bool = False, timeout: float = 120.0,
            drilled: bool = False) -> RunReport:
        """Reset the executor and sim, execute the plan (the injector drills it), judge the run.

        With `drilled`, the injector was to drill this run: a run it armed no drill for
        counts as not drilled.
        """
        client = self.client
        repaired, why = client.trigger(f'/{EXECUTOR_NODE}/reset')
        if not repaired:
            return RunReport(number, '', False, f'executor reset failed: {why}')
        ok, message = client.trigger(f'/{SIM_NODE}/reset')
        if not ok:
            return RunReport(number, '', False, f'sim reset failed: {message}')
        resets = message.split(':', 1)[0].split()[-1]
        client.wait_for_status(SIM_STATUS, lambda v: v.get('resets') == resets, 5.0)
        self.recording, self._record = [], record
        mark = client.status_mark
        try:
            report = client.execute(self.motion, timeout=timeout)
            # The executor may finish before the sim has stopped (at the goal, or after a
            # failure, when MuJoCo may still see a contact): record until it has. A failed
            # run's arm may have stood before (braking): a status after the failure counts.
            succeeded = report.result is Outcome.SUCCEEDED
            arm = client.wait_for_status(
                SIM_STATUS, lambda v: v.get('resets') == resets and v.get('state') == 'stopped'
                and (v.get('goal_reached') == 'True' or not succeeded), SETTLE_TIMEOUT,
                mark if succeeded else client.status_mark) or client.status(SIM_STATUS)
        finally:
            client.spin_until(lambda: False, 0.05)  # the last joint states of the run
            self._record = False
        values = report.values
        drill = self.drills.get(str(report.execution), '')
        sim = arm.values if arm is not None and arm.values.get('resets') == resets else {}
        collisions, contacts = int(sim.get('collisions', '0')), int(sim.get('contacts', '0'))
        ok, why = _judge(report, sim, collisions, contacts)
        lock = values.get('lock_configuration')
        locked_joint, landed = values.get('locked_joint', ''), report.number('lock_progress')
        missed = parse_drill(drill, None).missed(locked_joint, values.get('lock_phase', ''),
                                                 landed) if drill else \
            'the injector armed no drill' if drilled else ''
        return RunReport(
            number, drill, ok, why, locked_joint, landed, report.number('recovery_time_s'),
            parse_number(sim.get('goal_error_m')),
            parse_number(sim.get('goal_orientation_error_rad')),
            parse_number(sim.get('min_clearance_m')),
            collisions, np.array(parse_vector(lock)) if lock else None,
            np.array(self.recording) if record and self.recording else None, missed,
            contacts, parse_number(sim.get('tracking_error_rad')),
            parse_number(sim.get('tracking_displacement_m')),
            parse_number(sim.get('standstill_s')), parse_number(sim.get('braking_clearance_m')),
            report.number('braking_deviation_rad'))


def _judge(report, sim: dict, collisions: int, contacts: int) -> tuple[bool, str]:
    """Whether a run reached the goal without touching anything, and what to say of it.

    `report` is the executor's ExecutionReport, `sim` the sim's last status values.
    """
    reached = sim.get('goal_reached') == 'True'
    ok = report.result is Outcome.SUCCEEDED and reached and collisions == 0 and \
        contacts == 0 and bool(sim)
    if report.result is not Outcome.SUCCEEDED:
        return ok, report.message
    if collisions or contacts:
        return ok, f'{collisions} collision(s), {contacts} MuJoCo contact(s)'
    if not reached:
        return ok, 'the sim did not report the goal reached'
    return ok, report.message


def summarize(scene: Scene, motion: PlannedMotion, runs: Sequence[RunReport]) -> str:
    """Tabulate the plan, then one row per run, then the verdict."""
    tolerated = f', tolerates {", ".join(motion.tolerated_joints)}' \
        if motion.tolerated_joints and len(motion.tolerated_joints) < len(motion.joint_names) \
        else ''
    lines = [f'scene {scene.name}: plan {motion.plan_time_s:.3f} s (service round trip '
             f'{motion.round_trip_s:.3f} s), theta_s = '
             f'[{", ".join(f"{v:.3f}" for v in motion.theta_s)}] rad, '
             f'{len(motion.trajectory)} waypoints, S_F of {motion.surface.shape[0]} paths'
             f'{tolerated}']
    oriented = scene.task is not None and scene.task.kind in ('axis', 'pose')
    width = max(9, 2 + max((len(r.locked_joint) for r in runs), default=0))
    drill_width = max(16, 2 + max((len(r.drill) for r in runs), default=0))
    header = (f'{"run":>4}  {"drill":<{drill_width}}{"locked":<{width}}{"at [%]":>7}'
              f'{"recovery [s]":>14}{"goal err [m]":>14}'
              + (f'{"[rad]":>10}' if oriented else '') + f'{"min clear [m]":>15}  result')
    lines += [header, '-' * len(header)]
    for r in runs:
        at = f'{100 * r.lock_progress:.1f}' if np.isfinite(r.lock_progress) else '-'
        recovery = f'{r.recovery_time:.2f}' if np.isfinite(r.recovery_time) else '-'
        angle = f'{r.goal_orientation_error:>10.2e}' if oriented else ''
        result = 'reached' if r.ok else 'FAILED: ' + r.message
        lines.append(f'{r.run:>4}  {r.drill or "-":<{drill_width}}{r.locked_joint or "-":<{width}}'
                     f'{at:>7}{recovery:>14}{r.goal_error:>14.2e}{angle}'
                     f'{r.min_clearance:>15.4f}  {result}'
                     + (f'; NOT DRILLED: {r.missed}' if r.missed else ''))
    recoveries = np.array([r.recovery_time for r in runs if np.isfinite(r.recovery_time)])
    if len(recoveries):
        lines.append(f'recovery time p50 {np.percentile(recoveries, 50):.2f} s, p95 '
                     f'{np.percentile(recoveries, 95):.2f} s over {len(recoveries)} '
                     'recoveries')
    lines += braking_figures(runs) + physics_figures(runs)
    lines.append(f'{sum(r.ok for r in runs)}/{len(runs)} runs reached the goal without '
                 f'collision{count_drills(runs)}')
    return '\n'.join(lines)


def braking_figures(runs: Sequence[RunReport]) -> list[str]:
    """Say how the runs' locks braked: the smallest clearance, the largest deviation."""
    clearance = [r.braking_clearance for r in runs if np.isfinite(r.braking_clearance)]
    deviation = [r.braking_deviation for r in runs if np.isfinite(r.braking_deviation)]
    if not clearance and not deviation:
        return []
    return [f'braking after {len(clearance)} lock(s): smallest clearance '
            f'{min(clearance, default=float("nan")):.4f} m, largest deviation from the lock '
            f'point {max(deviation, default=float("nan")):.4f} rad (∞-norm, '
            f'{len(deviation)} measured)']


def physics_figures(runs: Sequence[RunReport]) -> list[str]:
    """Say the runs' MuJoCo figures: contacts, tracking error, standstill, clearance."""
    tracking = [r.tracking_error for r in runs if np.isfinite(r.tracking_error)]
    if not tracking:
        return []
    standstill = [r.standstill_time for r in runs if np.isfinite(r.standstill_time)]
    clearance = [r.min_clearance for r in runs if np.isfinite(r.min_clearance)]
    displacement = [r.tracking_displacement for r in runs
                    if np.isfinite(r.tracking_displacement)]
    return [f'physics: {sum(r.contacts for r in runs)} MuJoCo contacts, largest tracking '
            f'error {max(tracking):.4f} rad (a joint or the tool at most '
            f'{max(displacement, default=float("nan")) * 1000:.1f} mm from where commanded), '
            'standstill after a lock at most '
            + (f'{max(standstill):.3f} s' if standstill else '-')
            + f', smallest clearance {min(clearance, default=float("nan")):.4f} m']


def count_drills(runs: Sequence[RunReport]) -> str:
    """Say how many drilled runs were drilled as asked, and how the others missed ('' if none)."""
    drilled = [r for r in runs if r.drill or r.missed]
    if not drilled:
        return ''
    missed = [r for r in drilled if r.missed]
    text = f'; {len(drilled) - len(missed)}/{len(drilled)} drilled as asked'
    if missed:
        text += f', {len(missed)} not drilled (' + '; '.join(
            f'run {r.run} {r.drill or "-"}: {r.missed}' for r in missed) + ')'
    return text


def pick_run_to_draw(runs: Sequence[RunReport]) -> RunReport | None:
    """Pick the recorded run to draw: the recovery from a lock nearest mid-path, if any."""
    recorded = [r for r in runs if r.motion is not None and len(r.motion)]
    drilled = [r for r in recorded if r.locked_joint and r.lock_configuration is not None]
    if drilled:
        return min(drilled, key=lambda r: abs(r.lock_progress - 0.5))
    return recorded[0] if recorded else None


def write_motion_png(scene: Scene, report: RunReport, path: Path) -> Path:
    """Draw the recorded motion of a run and its moment of failure (figures module)."""
    from .figures import motion_figure, save_figure
    motion = report.motion
    joint = index = None
    title = f'{scene.name} through ROS: no failure'
    if report.locked_joint and report.lock_configuration is not None:
        joint = list(scene.robot.joint_names).index(report.locked_joint)
        index = int(np.argmin(np.linalg.norm(motion - report.lock_configuration, axis=1)))
        title = (f'{scene.name} through ROS: {report.locked_joint} locked at '
                 f'{report.lock_progress:.0%} of the nominal path, recovered')
    return save_figure(motion_figure(scene, motion, index, joint, title), path)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog='ftplan-bringup', description=__doc__.splitlines()[0])
    parser.add_argument('--scene', type=Path, required=True,
                        help='scene YAML (robot, obstacles, task)')
    parser.add_argument('--drill', action='append', default=[], metavar='JOINT@FRACTION',
                        help='one run locking JOINT at FRACTION (0..1) of the nominal path '
                        '(or at SECONDSs after the start); repeatable')
    parser.add_argument('--trials', type=int, default=0,
                        help='runs with a random joint locked at a random moment (0)')
    parser.add_argument('--seed', type=int, default=0, help='seed of the random drills (0)')
    parser.add_argument('--png', type=Path,
                        help='draw the executed motion of a drilled run (the one locked '
                        'nearest mid-path) here')
    parser.add_argument('--record', type=Path, metavar='FILE.mcap',
                        help='record every topic of the run here (MCAP, as rosbag2 writes it)')
    parser.add_argument('--speed', type=float, default=2.0,
                        help='fastest commanded joint speed [rad/s] (2.0)')
    parser.add_argument('--rate', type=float, default=100.0,
                        help='sim rate [Hz] of /joint_states (100)')
    parser.add_argument('--sim', choices=SIM_BACKENDS, default='kinematic',
                        help='the sim\'s backend: kinematic (exact) or mujoco (physics)')
    parser.add_argument('--timeout', type=float, default=120.0,
                        help='seconds a run may take (120)')
    parser.add_argument('-v', '--verbose', action='store_true', help='show the nodes\' logs')
    parser.add_argument('--ros-args', nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
    return parser


def _check(args: argparse.Namespace) -> Scene:
    """Return the scene once every argument is usable; InputError (exit 2) before any run."""
    scene = load_scene(args.scene)
    check_plannable(scene)  # else the nodes would start and refuse the plan later
    for text in args.drill:
        try:
            parse_drill(text, scene.robot.joint_names)
        except ValueError as error:
            raise InputError('--drill', str(error)) from None
    if args.trials < 0:
        raise InputError('--trials', f'must be >= 0, got {args.trials}')
    for name in ('speed', 'rate', 'timeout'):
        value = getattr(args, name)
        if not np.isfinite(value) or value <= 0:
            raise InputError(f'--{name}', f'must be a finite number > 0, got {value}')
    if args.png is not None:
        if args.png.suffix.lower() != '.png':
            raise InputError('--png', f'writes PNG files: give a path ending in .png, not '
                             f'{args.png}')
        if not args.png.resolve().parent.is_dir():
            raise InputError('--png', f'the folder of {args.png} does not exist')
    if args.record is not None:
        if args.record.suffix != '.mcap':
            raise InputError('--record', f'writes MCAP files: give a path ending in .mcap, '
                             f'not {args.record}')
        if not args.record.resolve().parent.is_dir():
            raise InputError('--record', f'the folder of {args.record} does not exist')
    return scene


def _open_recording(args: argparse.Namespace, scene: Scene,
                    argv: list[str] | None) -> BagWriter:
    """Create the --record file, naming the run's scene file and command in it."""
    command = shlex.join(['ftplan-bringup', *map(str, sys.argv[1:] if argv is None else argv)])
    try:
        return BagWriter(args.record, {'scene_file': str(args.scene.resolve()),
                                       'scene': scene.name, 'command': command})
    except OSError as error:
        raise InputError('--record', f'cannot write {args.record} ({error.strerror})') from None


def _plan_and_run(director: Director, args: argparse.Namespace, scene: Scene,
                  progress: Progress) -> int:
    """Plan, then run the drills and print the summary; return the exit code of `main`."""
    runs_wanted = len(args.drill) + args.trials or 1
    motion = director.plan()
    if not motion.succeeded:
        print(f'scene {scene.name}: {motion.message}')
        return 1
    progress.line(f'plan found in {motion.plan_time_s:.3f} s; approach: '
                  f'{motion.approach or "not reported"}; {runs_wanted} run(s)')
    runs: list[RunReport] = []
    for number in range(1, runs_wanted + 1):
        report = director.run(number, record=args.png is not None, timeout=args.timeout,
                              drilled=bool(args.drill or args.trials))
        runs.append(report)
        progress.line(f'run {number}/{runs_wanted}: {report.drill or "no drill"} -> '
                      f'{"reached" if report.ok else "FAILED: " + report.message}'
                      + (f'; NOT DRILLED: {report.missed}' if report.missed else ''))
    print(summarize(scene, motion, runs))
    png_run = pick_run_to_draw(runs)
    if args.png is not None and png_run is not None:
        try:
            print(f'wrote {write_motion_png(scene, png_run, args.png)}')
        except ImportError as error:
            print(f'ftplan-bringup: cannot draw {args.png}: {error}', file=sys.stderr)
            return 1
    return 0 if all(r.ok and not r.missed for r in runs) else 1


def main(argv: list[str] | None = None) -> int:
    """Run the bringup; return the exit code (0: every run reached the goal safely)."""
    args = _parser().parse_args(argv)
    try:
        scene = _check(args)
        writer = _open_recording(args, scene, argv) if args.record is not None else None
    except InputError as error:
        print(f'ftplan-bringup: error: {error}', file=sys.stderr)
        return 2
    progress = Progress(width=7)
    try:
        rclpy.init(args=['--ros-args'] + (args.ros_args or []),
                   signal_handler_options=SignalHandlerOptions.NO)
    except RclError as error:
        print(f'ftplan-bringup: error: cannot start ROS: {error}', file=sys.stderr)
        if writer is not None:
            writer.close()
        return 2
    # Ctrl-C and SIGTERM only set `interrupted`: the client raises KeyboardInterrupt from
    # its next wait. Raised by the signal itself, it could land inside rclpy's executor,
    # where it was lost (runs went on) or left it broken.
    interrupted = threading.Event()
    previous = {number: signal.signal(number, lambda signum, frame: interrupted.set())
                for number in (signal.SIGINT, signal.SIGTERM)}
    suite = client = recording = None
    try:
        if writer is not None:
            recording = Recording(writer)
        progress.line('starting the planner, executor, sim and injector nodes')
        suite = Suite(args.scene.resolve(), speed=args.speed, rate=args.rate, sim=args.sim,
                      drills=args.drill, random_drills=args.trials, seed=args.seed,
                      log_level=None if args.verbose else LoggingSeverity.WARN)
        if recording is not None:
            recording.node.subscribe_to_graph()  # the suite's topics, before any plan
        client = PlanClient(interrupted=interrupted)
        return _plan_and_run(Director(client, scene, progress), args, scene, progress)
    except KeyboardInterrupt:
        print('ftplan-bringup: interrupted; shutting the nodes down', file=sys.stderr)
        return 130
    except InputError as error:
        print(f'ftplan-bringup: error: {error}', file=sys.stderr)
        return 2
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
        if recording is not None:
            counts = recording.stop()
            print(f'wrote {args.record}: {sum(counts.values())} messages on {len(counts)} '
                  'topics')
        elif writer is not None:
            writer.close()
        if client is not None:
            client.destroy_node()
        if suite is not None:
            suite.shutdown()
        rclpy.try_shutdown()


if __name__ == '__main__':
    sys.exit(main())
