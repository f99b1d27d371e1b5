"""The runs of a recorded bringup, and the figure the bringup draws of one of them.

A recording of `ftplan-bringup --record` holds what the bringup judges and draws a run
by: the executor's status 'ftplan_executor: execution' on /diagnostics for each execution
(its state, the locked joint, where the lock landed, where the arm stood locked, the
outcome), the injector's 'ftplan_injector: drills' (the drill armed for each execution),
the arm on /joint_states, and the plan's status on /ftplan/plan/info (the digest of the
robot it was made for). `recorded_runs` cuts the joint states into runs, one per
execution, as the live bringup records them: from the sim's reset before it (or its
first status) until the sim reports the arm stopped after its last status (done or
failed), and makes the bringup's RunReport of each; `draw_recorded_run` draws one with
the bringup's own choice and drawing (`pick_run_to_draw`, `write_motion_png`): one
drawing path, fed live or from the file. The scene comes from the recording's 'ftplan'
metadata (the scene file of the run) or from the caller, and must be of the recorded
robot.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ftplan_msgs_py import read_diagnostic_status, read_joint_state

from ..bringup import SIM_STATUS, RunReport, pick_run_to_draw, write_motion_png
from ..core import InputError, Scene, load_scene
from ..core.model.robot import robot_digest
from ..nodes.plan_info import PLANNER_STATUS
from ..nodes.reporting import parse_number, parse_vector
from ..nodes.topics import DIAGNOSTICS, EXECUTOR_NODE, INJECTOR_NODE, JOINT_STATES, PLAN_INFO
from .bag_reader import Bag
from .bag_writer import FTPLAN_METADATA

EXECUTION_STATUS = f'{EXECUTOR_NODE}: execution'
DRILLS_STATUS = f'{INJECTOR_NODE}: drills'
_FINAL_STATES = ('done', 'failed')


@dataclass
class _Execution:
    """What the recording says of one execution (times [ns since the epoch])."""

    number: str
    start: int
    end: int | None = None
    resets: str | None = None                      # the sim's resets during the execution
    stopped: int | None = None                     # the sim's first 'stopped' after `end`
    values: dict = field(default_factory=dict)
    message: str = ''
    drill: str = ''


def recorded_scene(bag: Bag, scene_file: str | Path | None = None) -> Scene:
    """Load the scene of the recorded run (or `scene_file`); InputError if its robot differs.

    The robot must have the digest of the robot the recorded plan was made for (its
    status on /ftplan/plan/info), when the recording holds one.
    """
    where = '--scene'
    if scene_file is None:
        scene_file = bag.metadata.get(FTPLAN_METADATA, {}).get('scene_file')
        where = f'{bag.path} (its scene file)'
        if not scene_file:
            raise InputError('--scene', f'{bag.path} does not name the scene it recorded: '
                             'give it with --scene SCENE.yaml')
        if not Path(scene_file).is_file():
            raise InputError('--scene', f'the recorded scene file {scene_file} is not here: '
                             'give the scene with --scene SCENE.yaml')
    scene = load_scene(scene_file)
    recorded = _recorded_robot(bag)
    if recorded is not None and recorded != robot_digest(scene.robot):
        raise InputError(where, f'the robot of {Path(scene_file).name} (digest '
                         f'{robot_digest(scene.robot)}) is not the recorded one ({recorded}): '
                         'give the scene the run was recorded with')
    return scene


def recorded_runs(bag: Bag, joint_names: list[str]) -> list[RunReport]:
    """Return a RunReport per recorded execution, numbered from 1, with its joint motion.

    The motion (k, n) [rad] is every joint state from the sim's reset before the
    execution (or its first status) until the sim stopped after its last status (or the
    end of the recording), ordered as `joint_names`: the window the live bringup records.
    """
    timeline, states = _Timeline(), []
    for recorded in bag.messages([DIAGNOSTICS, JOINT_STATES]):
        if recorded.topic == JOINT_STATES:
            try:
                states.append((recorded.log_time, read_joint_state(recorded.message,
                                                                   joint_names)))
            except ValueError:
                pass  # another arm's, or malformed: the live bringup skips them too
            continue
        for status in recorded.message.status:
            timeline.take(status, recorded.log_time)
    runs = []
    for index, ex in enumerate(timeline.executions.values(), start=1):
        ex.drill = timeline.drills.get(ex.number, '')
        end = next((t for t in (ex.stopped, ex.end) if t is not None), float('inf'))
        motion = [q for t, q in states if ex.start <= t <= end]
        runs.append(_report(index, ex, np.array(motion) if motion else None))
    return runs


def draw_recorded_run(scene: Scene, runs: list[RunReport], path: Path) -> RunReport | None:
    """Draw the run the bringup would draw (the lock nearest mid-path) to `path`; None if none."""
    run = pick_run_to_draw(runs)
    if run is not None:
        write_motion_png(scene, run, path)
    return run


def describe_run(run: RunReport) -> str:
    """Say in one line what a recorded run did: drill, lock, outcome."""
    lock = (f'{run.locked_joint} locked at {run.lock_progress:.1%} of the nominal path'
            if run.locked_joint else 'no lock')
    states = 0 if run.motion is None else len(run.motion)
    return (f'run {run.run}: {run.drill or "no drill"}, {lock}, {states} joint states: '
            f'{"reached" if run.ok else "FAILED"} ({run.message})')


class _Timeline:
    """The executions, drills and sim resets of a recording's /diagnostics, in log order."""

    def __init__(self):
        self.executions: dict[str, _Execution] = {}
        self.drills: dict[str, str] = {}
        self._resets: str | None = None
        self._reset_time: int | None = None

    def take(self, status, log_time: int) -> None:
        """Note one status of /diagnostics received at `log_time` [ns since the epoch]."""
        try:
            reading = read_diagnostic_status(status)
        except ValueError:
            return
        values, number = reading.values, reading.values.get('execution')
        if reading.name == SIM_STATUS:
            self._take_sim(values, log_time)
        elif reading.name == DRILLS_STATUS and number and values.get('drill'):
            self.drills[number] = values['drill']
        elif reading.name == EXECUTION_STATUS and number:
            ex = self.executions.setdefault(
                number, _Execution(number, self._reset_time or log_time, resets=self._resets))
            if ex.end is None:
                ex.values, ex.message = dict(values), reading.message
                if values.get('state') in _FINAL_STATES:
                    ex.end = log_time

    def _take_sim(self, values: dict, log_time: int) -> None:
        """Note the sim's resets (where a run's motion starts) and stops (where it ends).

        A run ends where the sim, not yet reset again, first reports the arm stopped
        after the run's last status; at its next reset, at that last status.
        """
        resets = values.get('resets')
        for ex in self.executions.values():
            if ex.end is not None and ex.stopped is None:
                if resets != ex.resets:
                    ex.stopped = ex.end
                elif values.get('state') == 'stopped':
                    ex.stopped = log_time
        if resets != self._resets:
            self._resets, self._reset_time = resets, log_time


def _report(index: int, ex: _Execution, motion: np.ndarray | None) -> RunReport:
    """Make the bringup's RunReport of a recorded execution (the sim's values unknown: NaN)."""
    values = ex.values
    lock = values.get('lock_configuration')
    return RunReport(
        index, ex.drill, values.get('state') == 'done', ex.message,
        values.get('locked_joint', ''), parse_number(values.get('lock_progress')),
        parse_number(values.get('recovery_time_s')), parse_number(values.get('goal_error_m')),
        parse_number(values.get('goal_orientation_error_rad')),
        lock_configuration=np.array(parse_vector(lock)) if lock else None, motion=motion)


def _recorded_robot(bag: Bag) -> str | None:
    """Return the robot digest of the last recorded plan status, if any."""
    robot = None
    for recorded in bag.messages([PLAN_INFO]):
        for status in recorded.message.status:
            if status.name == PLANNER_STATUS:
                robot = next((pair.value for pair in status.values if pair.key == 'robot'),
                             robot)
    return robot
