"""The summary table of a study, and the Wilson interval its rates come with.

Rates are over the tasks that did not raise (outcome 'error' rows are counted apart):
a map's shares of each outcome, a sweep's feasible rate per number of random obstacles.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from .results import OUTCOMES
from .spec import Study

Z_95 = 1.959963984540054  # standard normal quantile of 0.975: two-sided 95 %


def wilson_interval(successes, trials, z: float = Z_95) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score interval (low, high) for a binomial rate; arrays broadcast.

    Better than p ± z·sqrt(p(1-p)/n) near 0 and 1 and for few trials (Wilson, 1927).
    Zero trials give (0, 1).
    """
    k = np.asarray(successes, dtype=float)
    n = np.asarray(trials, dtype=float)
    safe = np.maximum(n, 1.0)
    p = k / safe
    denominator = 1.0 + z ** 2 / safe
    centre = (p + z ** 2 / (2.0 * safe)) / denominator
    half = z * np.sqrt(p * (1.0 - p) / safe + z ** 2 / (4.0 * safe ** 2)) / denominator
    low = np.where(n > 0, np.clip(centre - half, 0.0, 1.0), 0.0)
    high = np.where(n > 0, np.clip(centre + half, 0.0, 1.0), 1.0)
    return low, high


def feasible_rate_by(table: pa.Table, column: str) -> dict[str, np.ndarray]:
    """Per value of `column`: value, tasks (not errors), feasible, rate, low, high, errors.

    Rows without a value (error rows whose inputs could not be drawn) count in no group.
    """
    values = np.asarray(table.column(column).to_numpy(zero_copy_only=False), dtype=float)
    feasible = _flags(table, 'feasible')
    errors = np.asarray(table.column('outcome').to_pylist()) == 'error'
    keys = np.unique(values[np.isfinite(values)])
    tasks = np.array([np.sum((values == v) & ~errors) for v in keys])
    wins = np.array([np.sum((values == v) & ~errors & feasible) for v in keys])
    low, high = wilson_interval(wins, tasks)
    return {'value': keys, 'tasks': tasks, 'feasible': wins,
            'rate': wins / np.maximum(tasks, 1), 'low': low, 'high': high,
            'errors': np.array([np.sum((values == v) & errors) for v in keys])}


def summarize(study: Study, table: pa.Table) -> str:
    """Tabulate the study's outcomes, times and clearances (and a sweep's rates)."""
    rows = table.num_rows
    lines = [f'study {study.name}: {study.kind} of {study.tasks} tasks '
             f'({rows} in the results), methods {", ".join(study.planner.methods)}']
    if rows == 0:
        return '\n'.join(lines)
    outcome = np.asarray(table.column('outcome').to_pylist())
    planned = rows - int(np.sum(outcome == 'error'))
    lines.append(f'{"outcome":<24}{"tasks":>8}{"share":>9}')
    for name in OUTCOMES:
        count = int(np.sum(outcome == name))
        share = f'{count / planned:.1%}' if name != 'error' and planned else '-'
        lines.append(f'{name:<24}{count:>8}{share:>9}')
    lines += _times_and_clearances(table)
    if study.kind == 'sweep':
        lines += _sweep_table(table)
    lines += _errors(table)
    return '\n'.join(lines)


def _times_and_clearances(table: pa.Table) -> list[str]:
    times = _floats(table, 'plan_time_s')
    times = times[np.isfinite(times)]
    lines = []
    if len(times):
        p50, p95 = np.percentile(times, [50, 95]) * 1e3
        lines.append(f'plan time p50 / p95: {p50:.0f} / {p95:.0f} ms over {len(times)} plans '
                     f'({times.sum():.1f} s in all)')
    clearance = _floats(table, 'min_clearance')[_flags(table, 'feasible')]
    finite = clearance[np.isfinite(clearance)]
    if len(finite):
        p5, p50 = np.percentile(finite, [5, 50])
        lines.append(f'minimum clearance of the failure-tolerant plans p5 / p50: '
                     f'{p5:.3f} / {p50:.3f} m')
    return lines


def _sweep_table(table: pa.Table) -> list[str]:
    rates = feasible_rate_by(table, 'random_obstacles')
    lines = ['feasible rate by number of random obstacles (95 % Wilson interval):',
             f'{"obstacles":>9}{"tasks":>8}{"feasible":>10}{"rate":>8}{"95 % interval":>18}'
             f'{"errors":>8}']
    for k in range(len(rates['value'])):
        lines.append(f'{int(rates["value"][k]):>9}{rates["tasks"][k]:>8}'
                     f'{rates["feasible"][k]:>10}{rates["rate"][k]:>8.1%}'
                     f'{rates["low"][k]:>11.1%} - {rates["high"][k]:.1%}'
                     f'{rates["errors"][k]:>7}')
    return lines


def _errors(table: pa.Table) -> list[str]:
    messages = [m for m in table.column('error').to_pylist() if m]
    if not messages:
        return []
    distinct = sorted(set(messages), key=messages.index)
    lines = [f'{len(messages)} tasks raised; {len(distinct)} distinct errors, e.g.:']
    lines += [f'  {message}' for message in distinct[:3]]
    return lines


def _floats(table: pa.Table, column: str) -> np.ndarray:
    return np.array([np.nan if v is None else v for v in table.column(column).to_pylist()],
                    dtype=float)


def _flags(table: pa.Table, column: str) -> np.ndarray:
    return np.array([bool(v) for v in table.column(column).to_pylist()], dtype=bool)
