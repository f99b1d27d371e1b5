"""A study's results: one Parquet file per finished chunk, written atomically, in one folder.

The folder holds `study.json` (the spec with defaults filled in, the base scene's
content, and their digest) and `chunk-NNNNNN.parquet` per finished chunk: one row per task,
columns as `result_schema` says. A chunk file is written under a temporary name, flushed to
disk and renamed, so it is either whole or absent, and a rerun skips the chunks it finds.
A folder whose study.json belongs to another spec is refused rather than mixed.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from ..core import InputError
from .spec import AXES, Study

MANIFEST = 'study.json'
FORMAT = 1                    # of the folder layout and the columns
OUTCOMES = ('failure_tolerant', 'not_failure_tolerant', 'unreachable', 'error')
_CHUNK_PREFIX = 'chunk-'
_TEMPORARY = '.tmp-'          # infix of chunk files being written


def result_schema(dim: int) -> pa.Schema:
    """Columns of a study's rows, for positions of `dim` axes (2: x, y; 3: x, y, z).

    task: index in the spec's enumeration; start_x.., goal_x.. [m]: the task;
    random_obstacles, obstacle_centers [m], obstacle_radii [m]: the spheres the study added
    to the base scene; feasible: a failure-tolerant plan exists (the planner's guarantee);
    outcome: one of OUTCOMES; reason: why not, from the planner; theta_s [rad]: the start
    configuration of the plan; plan_time_s [s]; min_clearance [m]: of the verified failure
    surface (inf without obstacles); method: the method that found the plan; error: what a task
    that raised said (null otherwise). Values that do not apply are null.
    """
    positions = [pa.field(f'{end}_{axis}', pa.float64())
                 for end in ('start', 'goal') for axis in AXES[:dim]]
    return pa.schema([
        pa.field('task', pa.int64(), nullable=False),
        *positions,
        pa.field('random_obstacles', pa.int32()),
        pa.field('obstacle_centers', pa.list_(pa.list_(pa.float64()))),
        pa.field('obstacle_radii', pa.list_(pa.float64())),
        pa.field('feasible', pa.bool_()),
        pa.field('outcome', pa.string()),
        pa.field('reason', pa.string()),
        pa.field('theta_s', pa.list_(pa.float64())),
        pa.field('plan_time_s', pa.float64()),
        pa.field('min_clearance', pa.float64()),
        pa.field('method', pa.string()),
        pa.field('error', pa.string()),
    ])


def rows_to_table(rows: list[dict], dim: int) -> pa.Table:
    """Make a table of `result_schema(dim)` from row dicts (missing keys are null)."""
    return pa.Table.from_pylist(rows, schema=result_schema(dim))


class ResultStore:
    """The results folder of one study."""

    def __init__(self, folder: str | Path, study: Study):
        self.folder = Path(folder)
        self.study = study

    def open(self) -> None:
        """Create the folder and its study.json, or check that they belong to this study.

        Raises InputError (field `--out`) for a folder holding another study's results.
        Deletes chunk files left half-written by a run that was killed.
        """
        manifest = self.folder / MANIFEST
        digest = self.study.digest()
        if manifest.exists():
            try:
                theirs = json.loads(manifest.read_text()).get('digest')
            except (ValueError, AttributeError):
                theirs = None
            if theirs != digest:
                raise InputError('--out', f'{self.folder} holds the results of another study '
                                 f'(its {MANIFEST} differs from this spec): use another folder')
        elif any(self.folder.glob(f'{_CHUNK_PREFIX}*')):
            raise InputError('--out', f'{self.folder} holds chunk files but no {MANIFEST}: '
                             'use another folder')
        else:
            self.folder.mkdir(parents=True, exist_ok=True)
            record = {'format': FORMAT, 'digest': digest, 'name': self.study.name,
                      'kind': self.study.kind, 'tasks': self.study.tasks,
                      'chunks': self.study.chunks, 'study': self.study.describe(),
                      'columns': result_schema(self.study.dim).names}
            _write_atomically(manifest, lambda f: f.write(
                json.dumps(record, indent=1, allow_nan=False).encode()))
        for stale in self.folder.glob(f'.*{_TEMPORARY}*'):
            stale.unlink(missing_ok=True)

    def chunk_path(self, chunk: int) -> Path:
        """Where chunk `chunk` is stored."""
        return self.folder / f'{_CHUNK_PREFIX}{chunk:06d}.parquet'

    def finished_chunks(self) -> set[int]:
        """Chunks with a file in the folder."""
        if not self.folder.is_dir():
            return set()
        found = set()
        for path in self.folder.glob(f'{_CHUNK_PREFIX}*.parquet'):
            number = path.stem[len(_CHUNK_PREFIX):]
            if number.isdigit() and int(number) < self.study.chunks:
                found.add(int(number))
        return found

    def write(self, chunk: int, table: pa.Table) -> Path:
        """Store chunk `chunk` atomically; its rows must be exactly its tasks, in order."""
        expected = list(self.study.chunk_tasks(chunk))
        if table.column('task').to_pylist() != expected:
            raise ValueError(f'chunk {chunk} must hold tasks {expected[0]}..{expected[-1]} '
                             'in order, once each')
        path = self.chunk_path(chunk)
        _write_atomically(path, lambda f: pq.write_table(table, f))
        return path

    def read(self) -> pa.Table:
        """All finished chunks' rows, in task order (a partial study gives fewer rows)."""
        schema = result_schema(self.study.dim)
        tables = [pq.read_table(self.chunk_path(c), schema=schema)
                  for c in sorted(self.finished_chunks())]
        return pa.concat_tables(tables) if tables else schema.empty_table()


def _write_atomically(path: Path, write) -> None:
    """Write through `write(file)` to a temporary name beside `path`, sync, then rename."""
    temporary = path.with_name(f'.{path.name}{_TEMPORARY}{os.getpid()}')
    try:
        with open(temporary, 'wb') as file:
            write(file)
            file.flush()
            os.fsync(file.fileno())
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)
