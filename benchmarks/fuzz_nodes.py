"""Fuzz the running nodes with malformed messages and requests (issue 10), the long run.

    .venv/bin/python benchmarks/fuzz_nodes.py [--per-input 10000] [--seed 0] [--json out.json]

The planner, executor, sim and injector run as the installed executables (`make install`),
a second planner waits for its robot on /robot_description in a ROS domain of its own.
Every input of theirs (/joint_states, /ftplan/obstacles, /ftplan/locked_joint,
/ftplan/joint_command, the plan's latched topics, /diagnostics, /robot_description) gets
`--per-input` malformed messages, the plan service as many malformed requests and the
Trigger services (execute, the resets) as many calls in a random order. Passes (exit 0)
with no death, resident memory grown by at most 10 % per process, the last good plan kept
and a valid request afterwards answered correctly (test/ros/fuzzing.py says how each is
checked). `make test` runs the same with 46 per input (test/ros/test_ros_fuzz.py).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test' / 'ros'))  # the tests' domain claim and fuzzing

from ros_domain import claim_domain  # noqa: E402

claim_domain()
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')

from fuzzing import FuzzRun  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--per-input', type=int, default=10_000)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--rate', type=float, default=2000.0,
                        help='messages per second at most (2000)')
    parser.add_argument('--json', type=Path, help='write the report here')
    args = parser.parse_args()
    logs = Path(tempfile.mkdtemp(prefix='ftplan-fuzz-'))
    started = time.perf_counter()

    def progress(line: str) -> None:
        print(f'[{time.perf_counter() - started:7.1f} s] {line}', file=sys.stderr, flush=True)

    report = FuzzRun(logs, claim_domain(environment=False), args.seed, args.rate,
                     progress).run(args.per_input)
    print(report.summary())
    problems = report.problems()
    print('PASSED' if not problems else 'FAILED: ' + '; '.join(problems))
    print(f'node logs: {logs}')
    if args.json:
        args.json.write_text(json.dumps({**report.__dict__, 'problems': problems,
                                         'messages': report.messages}, indent=1))
    return 0 if not problems else 1


if __name__ == '__main__':
    sys.exit(main())
