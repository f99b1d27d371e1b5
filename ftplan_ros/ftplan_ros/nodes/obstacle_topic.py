"""A node's /ftplan/obstacles: every update applied, in order, and lost ones named.

The planner, the executor and the sim read the topic alike. Its subscription
(OBSTACLE_QOS, qos.py) keeps up to OBSTACLE_QUEUE_DEPTH updates, so a burst waits for a
busy node instead of overwriting what it has not read, and one callback at a time applies
them in the order received. Each update's publication sequence number
(obstacle_updates.py) tells when some were lost all the same; then `ObstacleSet.lost`
says so until a full set (a MarkerArray whose first marker is DELETEALL) is applied.

Every update is reported as '<node>: obstacles' on /diagnostics, with the values
`obstacles` (how many came from the topic), `update` (its publication sequence number),
`obstacle_set` (the digest of the static and topic obstacles, as the plan status names
them) and `complete`: OK; ERROR for an array refused whole (the set stays as it was,
and is incomplete: what was published is not what is held) and while updates are lost.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from contextlib import nullcontext

from rclpy.node import Node
from visualization_msgs.msg import MarkerArray

from .obstacle_updates import Gap, UpdateStreams
from .obstacles import ObstacleSet, obstacle_set_key
from .qos import OBSTACLE_QOS
from .reporting import Diagnostics
from .topics import OBSTACLES

FULL_SET_FIX = 'publish a full set (a MarkerArray whose first marker is DELETEALL)'


class ObstacleTopic:
    """A node's ObstacleSet (`obstacles`), fed by /ftplan/obstacles; reports on its updates.

    `lock` (the node's) is held while the set changes; `on_update()` runs after an
    update that changed the set or found updates lost. With `log`, every update is
    logged, not only the problems.
    """

    def __init__(self, node: Node, diagnostics: Diagnostics, *, lock: threading.Lock | None = None,
                 on_update: Callable[[], None] | None = None, log: bool = False):
        self._node = node
        self._diagnostics = diagnostics
        self.obstacles = ObstacleSet(None)
        self._lock = lock if lock is not None else nullcontext()
        self._on_update = on_update
        self._log = log
        self._streams = UpdateStreams()
        self.subscription = node.create_subscription(
            MarkerArray, OBSTACLES, self.obstacles_callback, OBSTACLE_QOS)

    def obstacles_callback(self, msg: MarkerArray, info: dict) -> None:
        """Apply one update, in the order received; name the updates lost before it."""
        number = info.get('publication_sequence_number')
        gap = self._streams.receive(number)
        found = '' if gap is None else self._describe(gap)
        problem = ''
        with self._lock:
            was_lost = self.obstacles.lost
            try:
                self.obstacles.update(msg, found)
            except ValueError as error:
                problem = str(error)
            lost = self.obstacles.lost
            values = self._values(number)
            waiting = self.obstacles.pending
        self._report(problem, lost or (found if waiting else ''), was_lost, waiting, values)
        if self._on_update is not None and (not problem or lost != was_lost):
            self._on_update()

    def _describe(self, gap: Gap) -> str:
        """Say which updates were lost and who published them (a graph query: rare)."""
        try:
            names = sorted({f'{info.node_namespace.rstrip("/")}/{info.node_name}'
                            for info in self._node.get_publishers_info_by_topic(OBSTACLES)})
        except Exception:  # noqa: BLE001 - the graph may be gone at shutdown; the gap stays
            names = []
        source = f'from {names[0]}' if len(names) == 1 else \
            f'from one of {", ".join(names)}' if names else 'from a publisher that has left'
        return f'obstacle updates were lost ({gap.describe()}, {source})'

    def _values(self, number: int | None) -> dict[str, object]:
        scene = self.obstacles.scene()
        return {'obstacles': len(self.obstacles), 'update': number or '',
                'obstacle_set': '' if scene is None else obstacle_set_key(scene.obstacles),
                'complete': not self.obstacles.lost}

    def _report(self, problem: str, lost: str, was_lost: str, waiting: int,
                values: dict) -> None:
        """Report an update: refused, or with updates lost (found now or before), or applied."""
        kept = values['obstacles']
        if problem:
            self._diagnostics.report(
                'obstacles', 'ERROR', f'ignored obstacle markers: {problem}; the set is not '
                f'the one published: {FULL_SET_FIX}; holding the {kept} previous meanwhile',
                values, log=True)
        elif lost:
            self._diagnostics.report('obstacles', 'ERROR', f'{lost}: {FULL_SET_FIX}; '
                                     f'holding {kept} obstacles meanwhile', values,
                                     log=lost != was_lost or self._log)
        elif waiting:
            self._diagnostics.report('obstacles', 'OK', f'{waiting} obstacle marker arrays '
                                     'wait for the robot', values, log=self._log)
        else:
            again = ' (a full set: the updates lost before it no longer matter)' \
                if was_lost else ''
            self._diagnostics.report('obstacles', 'OK', f'{kept} obstacles from '
                                     f'{OBSTACLES}{again}', values,
                                     log=self._log or bool(was_lost))
        if not self._streams.numbered:
            self._node.get_logger().warning(
                f'{OBSTACLES}: this middleware does not number its messages, so lost '
                'obstacle updates cannot be detected', once=True)

    def report_rebase(self, problems: list[str]) -> None:
        """Report what came of the updates that waited for the robot (ObstacleSet.rebase).

        `problems` are the marker arrays refused; updates lost among them make the set
        incomplete, reported like a gap.
        """
        for problem in problems:
            self._diagnostics.rejected('obstacles', f'ignored obstacle markers: {problem}')
        lost = self.obstacles.lost
        if lost:
            self._diagnostics.report('obstacles', 'ERROR', f'{lost}: {FULL_SET_FIX}',
                                     self._values(None), log=True)
