"""Fuzz the URDF and SRDF readers, and Pinocchio behind them, without dying of a crash.

    .venv/bin/python benchmarks/fuzz_descriptions.py [--cases 10000] [--seed 0] [--out DIR]

Case k draws a URDF and an SRDF from random.Random(f'{seed}:{k}') (test/descriptions.py:
random trees with cycles, second parents and roots, repeated and missing names, numbers
that are not decimal, finite or bounded, unknown and deeply nested tags, hostile XML).
The readers (pure Python) run here; every URDF they accept is built by
`robot_from_urdf` (Pinocchio, with the SRDF when it was accepted too) in child
processes, in batches: a child that dies (a segfault) names the case it was building,
whose URDF and SRDF are written to --out, and the batch goes on in a new child. Passes
(exit 0) when no child died and every failure was an InputError naming its field.
`make test` runs 300 URDFs and 150 SRDFs (test_urdf_structure.py, test_srdf.py).
"""

from __future__ import annotations

import argparse
import json
import random
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test'))  # the documents' generator and the test meshes

from descriptions import PANDA_URDF, random_srdf, random_urdf  # noqa: E402
from ftplan_testing import TETRAHEDRON, write_binary_stl  # noqa: E402

from ftplan_ros.core.errors import InputError  # noqa: E402
from ftplan_ros.core.model.srdf import read_srdf  # noqa: E402
from ftplan_ros.core.model.urdf_structure import read_urdf  # noqa: E402

FIELDS = ('robot.file', 'robot.srdf', 'robot.tip_link', 'robot.base_link')


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--cases', type=int, default=10_000)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--batch', type=int, default=250, help='URDFs per child process')
    parser.add_argument('--out', type=Path, help='where crashing inputs go (default: a '
                        'temporary folder)')
    parser.add_argument('--worker', type=Path, help=argparse.SUPPRESS)  # the child's mode
    args = parser.parse_args()
    if args.worker:
        return build_batch(args.worker)
    out = args.out or Path(tempfile.mkdtemp(prefix='ftplan-fuzz-descriptions-'))
    out.mkdir(parents=True, exist_ok=True)
    write_meshes(out)
    started = time.perf_counter()
    counts, accepted = read_cases(args.cases, args.seed)
    crashes = build_in_children(accepted, args.batch, out, counts)
    seconds = time.perf_counter() - started
    print(f'{args.cases} cases (seed {args.seed}) in {seconds:.0f} s:')
    for key in sorted(counts):
        print(f'  {key:<36} {counts[key]}')
    print(f'  {"child processes that died":<36} {len(crashes)}')
    for case in crashes:
        print(f'    case {case}: {out}/crash_{case}.urdf (and .srdf)')
    unexpected = sum(n for key, n in counts.items() if 'other' in key)
    return 0 if not crashes and not unexpected else 1


def read_cases(cases: int, seed: int) -> tuple[Counter, list[dict]]:
    """Run the readers on every case; return the counts and the URDFs to build."""
    counts: Counter = Counter()
    accepted = []
    panda_links = read_urdf(PANDA_URDF.read_text()).links
    for case in range(cases):
        rng = random.Random(f'{seed}:{case}')
        text = random_urdf(rng)
        srdf = random_srdf(rng, rng.choice([[], list(panda_links)]))
        read(lambda s=srdf: read_srdf(s, panda_links), 'SRDF for the Panda', counts)
        urdf = read(lambda t=text: read_urdf(t), 'URDF', counts)
        if urdf is None:
            continue
        srdf = random_srdf(rng, list(urdf.links))
        if read(lambda s=srdf, u=urdf: read_srdf(s, u.links), 'SRDF for the URDF',
                counts) is None:
            srdf = None
        accepted.append({'case': case, 'urdf': text, 'srdf': srdf,
                         'tip': rng.choice(urdf.links)})
    return counts, accepted


def read(call, what: str, counts: Counter):
    """Call a reader; count its outcome; return its result, None when it refused."""
    try:
        result = call()
    except InputError as error:
        counts[f'{what} refused' if error.field in FIELDS else f'other {what} {error}'] += 1
        return None
    except Exception as error:  # noqa: BLE001 - counted, and the run fails
        counts[f'other {what} {error!r}'] += 1
        return None
    counts[f'{what} accepted'] += 1
    return result


def build_in_children(accepted: list[dict], batch: int, out: Path, counts: Counter,
                      ) -> list[int]:
    """Build the accepted URDFs in child processes; return the cases a child died on."""
    crashes = []
    pending = list(accepted)
    while pending:
        chunk, pending = pending[:batch], pending[batch:]
        run = subprocess.run([sys.executable, __file__, '--worker', str(out)],
                             input=json.dumps(chunk), capture_output=True, text=True)
        done = {}
        for line in run.stdout.splitlines():
            case, outcome = line.split(' ', 1)
            done[int(case)] = outcome
        for outcome in done.values():
            counts[f'built: {outcome}'] += 1
        if run.returncode > 0:  # Python failed in the child: no case is to blame
            raise SystemExit(f'a child process failed:\n{run.stderr[-2000:]}')
        if run.returncode < 0:  # killed by a signal (SIGSEGV: -11) building the next case
            rest = [item for item in chunk if item['case'] not in done]
            crash = rest[0]
            crashes.append(crash['case'])
            (out / f'crash_{crash["case"]}.urdf').write_text(crash['urdf'])
            (out / f'crash_{crash["case"]}.srdf').write_text(crash['srdf'] or '')
            print(f'case {crash["case"]}: the child died ({run.returncode}) '
                  f'{run.stderr[-300:]}', file=sys.stderr)
            pending = rest[1:] + pending
    return crashes


def build_batch(meshes: Path) -> int:
    """The child: build each URDF on stdin, one line per case ('<case> <outcome>')."""
    from ftplan_ros.core.io.scene_file import robot_from_urdf
    for item in json.loads(sys.stdin.read()):
        try:
            robot_from_urdf(item['urdf'], item['tip'], srdf=item['srdf'],
                            mesh_dirs=[str(meshes)])
            outcome = 'arm'
        except InputError as error:
            outcome = (f'InputError {error.field}' if error.field in FIELDS
                       else f'other {error}')
        except Exception as error:  # noqa: BLE001 - counted, and the run fails
            outcome = f'other {error!r}'
        print(item['case'], outcome, flush=True)
    return 0


def write_meshes(folder: Path) -> None:
    """The meshes the drawn URDFs name: a tetrahedron and a file that is no mesh."""
    write_binary_stl(folder / 'tet.stl', *TETRAHEDRON)
    (folder / 'garbage.stl').write_bytes(b'solid \x00\xff not a mesh\n' * 7)


if __name__ == '__main__':
    sys.exit(main())
