"""Progress lines on stderr for work that takes more than a second (`ftplan`, the bringup).

Each line starts with the time elapsed, e.g. `[  1.25 s] tracing self-motion manifolds`;
counted work adds the rate and the time left, e.g. `1200/3721 tasks, 96.3 tasks/s,
ETA 26 s`.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO


class Progress:
    """Print stages and counts of the work with the time elapsed.

    `clock` returns seconds (time.perf_counter; tests pass their own); `quiet` prints
    nothing; `width` is the characters of the elapsed seconds (the bringup's lines use 7).
    """

    def __init__(self, stream: TextIO = sys.stderr,
                 clock: Callable[[], float] = time.perf_counter, quiet: bool = False,
                 width: int = 6):
        self.stream = stream
        self.clock = clock
        self.quiet = quiet
        self.width = width
        self.started = clock()
        self.last = -1.0
        self.base = (self.started, 0)  # (time, items done then): where the rate counts from

    def line(self, text: str) -> None:
        """Print a stage of the work with the time elapsed."""
        if not self.quiet:
            print(f'[{self.clock() - self.started:{self.width}.2f} s] {text}', file=self.stream,
                  flush=True)

    def begin(self, done: int = 0) -> None:
        """Count the rate from now, `done` items being finished already (e.g. by an earlier run)."""
        self.base = (self.clock(), done)

    def count(self, done: int, total: int, unit: str = '') -> None:
        """Print `done/total`, the rate and the time left, at most once a second and at the end.

        The rate is over the items done since `begin` (or since this object was made).
        """
        now = self.clock()
        if done != total and now - self.last < 1.0:
            return
        self.last = now
        text = f'{done}/{total}' + (f' {unit}' if unit else '')
        since, done_before = self.base
        if now > since and done > done_before:
            rate = (done - done_before) / (now - since)
            text += f', {rate:.1f} {unit or "items"}/s'
            if done < total:
                text += f', ETA {_duration((total - done) / rate)}'
        self.line(text)


def _duration(seconds: float) -> str:
    """Seconds as '42 s', '12.5 min' or '3.2 h'."""
    if seconds < 120:
        return f'{seconds:.0f} s'
    if seconds < 7200:
        return f'{seconds / 60:.1f} min'
    return f'{seconds / 3600:.1f} h'
