"""The sim's watch over the arm's motion: collisions, and the smallest clearance [m].

Every sample of the motion is screened cheaply (the checker's bound, exact only where it
sees a contact), so a collision is exact; the smallest clearance is measured exactly at
the CLOSEST_SAMPLES samples the screen found closest since it was last measured (at each
stop of the arm): the screen alone would report its bound. The motion from a lock to
the next stop, the braking, has a smallest clearance of its own.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np

from ftplan_ros.execution.options import Obstacles

CLOSEST_SAMPLES = 8  # samples measured exactly for the smallest clearance, at each stop


@dataclass(frozen=True, eq=False)
class Collision:
    """The arm at `configuration` (n,) [rad] in collision, `clearance` [m] deep (<= 0, or NaN)."""

    configuration: np.ndarray
    clearance: float


class ClearanceMonitor:
    """Count collisions and keep the smallest clearance of the samples checked."""

    def __init__(self, obstacles: Obstacles):
        self.obstacles = obstacles
        self.clear()

    def clear(self) -> None:
        """Start counting afresh (a new arm, or a reset)."""
        self.collisions = 0
        self.min_clearance = float('inf')
        self.braking_clearance = float('inf')  # from a lock to the stop after it
        self._braking = False
        # The samples with the smallest screened clearance since the last measurement, as
        # a heap of (-bound, sample number, configuration).
        self._closest: list[tuple[float, int, np.ndarray]] = []
        self._samples = 0
        self._in_collision = False

    def check(self, samples: np.ndarray) -> Collision | None:
        """Check samples (k, n) [rad] of the motion; return the collision they begin, if any.

        A collision counts once until a check finds the arm clear again.
        """
        clearance = self.obstacles.checker.min_clearance(samples, needed=0.0)
        worst = int(np.argmin(clearance))
        colliding = not clearance[worst] > 0.0  # a NaN clearance reads as a collision
        if colliding:
            self.min_clearance = min(self.min_clearance, float(clearance[worst]))
            if self._braking:
                self.braking_clearance = min(self.braking_clearance, float(clearance[worst]))
        for bound, q in zip(clearance.tolist(), samples, strict=True):
            self._samples += 1
            entry = (-bound, self._samples, q.copy())
            if len(self._closest) < CLOSEST_SAMPLES:
                heapq.heappush(self._closest, entry)
            elif -bound > self._closest[0][0]:
                heapq.heapreplace(self._closest, entry)
        began = colliding and not self._in_collision
        self._in_collision = colliding
        if began:
            self.collisions += 1
            return Collision(samples[worst].copy(), float(clearance[worst]))
        return None

    def begin_braking(self) -> None:
        """Count what is checked from now to the next stop as braking (a joint locked)."""
        self.measure_closest()
        self._braking = True

    def measure_closest(self) -> None:
        """Measure exactly the samples the screen found closest since the last time."""
        braking, self._braking = self._braking, False
        if not self._closest:
            return
        samples = np.array([q for _, _, q in self._closest])
        self._closest = []
        exact = float(self.obstacles.checker.min_clearance(samples).min())
        self.min_clearance = min(self.min_clearance, exact)
        if braking:
            self.braking_clearance = min(self.braking_clearance, exact)
