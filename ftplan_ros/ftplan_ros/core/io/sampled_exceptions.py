"""A robot's sampled self-collision exceptions: sampled once, then read from the cache.

A robot that comes without an SRDF or a `disabled_collisions` list gets MoveIt's sampled
exceptions (collision/self_collision.py). Sampling takes seconds, so the counts of
touching samples are kept in the cache (io/cache.py) under the robot's fingerprint: its
digest (joint names, limits, kinematics and collision geometry: model/robot.robot_digest)
with the number of samples and the seed. The same robot loaded again reads them; a
changed model samples again. The choice, each pair with why, is logged.
"""

from __future__ import annotations

import logging
import time
from dataclasses import replace
from typing import Any

import numpy as np

from ..collision.self_collision import (
    ALWAYS_FRACTION,
    SAMPLES,
    Sampling,
    choose_exceptions,
    sample_collisions,
    sampled_pairs,
)
from ..errors import InputError
from ..model.chain import ChainModel
from ..model.robot import robot_digest
from ..model.spatial import SpatialArm
from ..validation import check_keys, integer, mapping
from .cache import entry_path, read_entry, write_entry

log = logging.getLogger(__name__)

KIND = 'self_collision'
FORMAT = 1  # of the cache entries: raise it when what they hold changes
MOST_SAMPLES = 1_000_000


def parse_sampling(data: Any, where: str = 'robot.self_collision_sampling') -> Sampling:
    """Validate a robot's `self_collision_sampling` ({samples, never}); None: the defaults."""
    if data is None:
        return Sampling()
    data = mapping(data, where)
    check_keys(data, where, required=(), optional=('samples', 'never'))
    samples = integer(data.get('samples', SAMPLES), f'{where}.samples', least=100)
    if samples > MOST_SAMPLES:
        raise InputError(f'{where}.samples', f'must be at most {MOST_SAMPLES}, got {samples}')
    never = data.get('never', True)
    if not isinstance(never, bool):
        raise InputError(f'{where}.never', f'must be true or false, got {never!r}')
    return Sampling(samples=samples, never=never)


def sampled_exceptions(model: ChainModel, sampling: Sampling | None = None,
                       ) -> frozenset[tuple[int, int]]:
    """Return the model's sampled exceptions (link pairs a < b), from the cache if it has them."""
    sampling = sampling or Sampling()
    bare = replace(model, disabled_pairs=frozenset())
    key = f'{robot_digest(SpatialArm(bare))}-{sampling.samples}-{sampling.seed}-v{FORMAT}'
    counts = _cached_counts(bare, key, sampling.samples)
    if counts is not None:
        source = f'read from {entry_path(KIND, key)}'
    else:
        started = time.perf_counter()
        counts = sample_collisions(bare, sampling.samples, np.random.default_rng(sampling.seed))
        path = write_entry(KIND, key, {'samples': sampling.samples, 'seed': sampling.seed,
                                       'pairs': [[a, b, n] for (a, b), n in counts.items()]})
        source = (f'sampled in {time.perf_counter() - started:.1f} s'
                  f'{"" if path is None else f", kept in {path}"}')
    exceptions = choose_exceptions(bare, counts, sampling.samples, sampling.never)
    log.info('%s', describe_exceptions(bare, counts, exceptions, sampling, source))
    return frozenset(exceptions)


def describe_exceptions(model: ChainModel, counts: dict[tuple[int, int], int],
                        exceptions: dict[tuple[int, int], str], sampling: Sampling,
                        source: str) -> str:
    """Say which pairs are exempt and why, and which are checked with how often they touch."""
    names = model.link_names

    def share(pair: tuple[int, int]) -> str:
        return f'{100.0 * counts[pair] / sampling.samples:.1f} %'

    exempt = [f'{names[a]}/{names[b]} ({why}' + (f', {share((a, b))})' if why == 'always'
                                                 else ')')
              for (a, b), why in exceptions.items()]
    checked = [f'{names[a]}/{names[b]} ({share((a, b))})' for a, b in sorted(counts)
               if (a, b) not in exceptions]
    never = '' if sampling.never else '; pairs touching in no sample stay checked (never: false)'
    return (f'self-collision exceptions of robot {model.name!r} (it has no SRDF or '
            f'disabled_collisions): MoveIt\'s, from {sampling.samples} random configurations '
            f'({source}): exempt {", ".join(exempt) or "none"}; checked, with the share of '
            f'samples touching: {", ".join(checked) or "none"}{never} (always: >= '
            f'{ALWAYS_FRACTION:.0%})')


def _cached_counts(model: ChainModel, key: str, samples: int,
                   ) -> dict[tuple[int, int], int] | None:
    """Return the cached counts of the model, or None when the entry is missing or not its own."""
    data = read_entry(KIND, key)
    if data is None:
        return None
    expected = set(sampled_pairs(model))
    try:
        counts = {(int(a), int(b)): int(n) for a, b, n in data['pairs']}
        valid = (data['samples'] == samples and set(counts) == expected
                 and all(0 <= n <= samples for n in counts.values()))
    except (KeyError, TypeError, ValueError):
        valid = False
    if not valid:
        log.warning('ignoring the cache entry %s: it does not hold this robot\'s sampled '
                    'self-collision counts', entry_path(KIND, key))
        return None
    return counts
