"""Run a study on a Dask cluster: chunks of tasks go out as Dask tasks, rows come back.

The driver (this module) submits one Dask task per unfinished chunk, writes each chunk's
Parquet file as its rows arrive and prints progress; workers run `tasks.run_chunk`. A
worker plugin loads the numba continuation kernel once per worker process, so no plan
time includes it.

When a worker dies, the scheduler gives its chunks to another worker (a LocalCluster's
nanny also starts a new one). A chunk that has taken down too many workers (Dask's
`distributed.scheduler.allowed-failures`) is split into one-task chunks; a task that
still takes its worker down becomes an error row. Any other failure of a chunk means the
workers cannot run ftplan at all (e.g. it is not installed there): the study stops with
StudyError, keeping what it wrote.
"""

from __future__ import annotations

import hashlib
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field

import pyarrow as pa
from distributed import Client, WorkerPlugin, as_completed
from distributed.scheduler import KilledWorker

from ..core import load_kernels
from .results import ResultStore, rows_to_table
from .spec import Study
from .tasks import ChunkResult, error_row, run_chunk


class StudyError(RuntimeError):
    """The workers cannot run the study; the chunks written so far stay."""


class KernelLoader(WorkerPlugin):
    """Load the compiled continuation kernel for the study's robot when a worker starts.

    Named after the robot and idempotent: a second study of the same robot on the same
    cluster does not load it again.
    """

    idempotent = True

    def __init__(self, robot):
        self.robot = robot
        self.name = f'ftplan-kernels-{hashlib.sha256(repr(robot).encode()).hexdigest()[:12]}'

    def setup(self, worker) -> None:
        """Run once per worker process (and again in a replacement worker)."""
        load_kernels(self.robot)


@dataclass
class ChunkTiming:
    """When and where a chunk (or a piece of one) ran [s since the epoch]."""

    chunk: int
    tasks: int
    worker: str
    started: float
    finished: float


@dataclass
class StudyRun:
    """What one run of the command did."""

    tasks: int                       # in the study
    chunks: int                      # in the study
    skipped_chunks: int              # found finished in the folder
    computed_chunks: int = 0         # written by this run
    split_chunks: int = 0            # split into one-task pieces after killing workers
    started: float = 0.0             # [s since the epoch] when the first chunk was submitted
    finished: float = 0.0            # [s since the epoch] when the last chunk was written
    timings: list[ChunkTiming] = field(default_factory=list)

    @property
    def complete(self) -> bool:
        """Whether every chunk of the study is in the folder."""
        return self.skipped_chunks + self.computed_chunks == self.chunks


def run_study(study: Study, store: ResultStore, client: Client, progress=None,
              plan_task: Callable[[Study, int], dict] | None = None) -> StudyRun:
    """Compute the study's unfinished chunks on `client`'s cluster and store them.

    `progress` has `line(text)` and `count(done, total, unit)` (progress.Progress); `plan_task`
    replaces `tasks.plan_study_task` on the workers (benchmarks time Dask with a no-op).
    Raises StudyError when a chunk fails for another reason than a dying worker.
    """
    store.open()
    finished = store.finished_chunks()
    todo = [c for c in range(study.chunks) if c not in finished]
    run = StudyRun(study.tasks, study.chunks, len(finished))
    if not todo:
        return run
    progress = progress or _Silent()
    done = sum(len(study.chunk_tasks(c)) for c in finished)
    progress.line(f'{study.tasks} tasks in {study.chunks} chunks of {study.chunk}; '
                  f'{len(finished)} chunks already done; {_describe_cluster(client)}')
    client.register_plugin(KernelLoader(study.scene.robot))
    if not client.scheduler_info(n_workers=-1)['workers']:
        progress.line('the scheduler has no workers yet: waiting for the first')
        client.wait_for_workers(1)
    progress.begin(done)
    run.started = time.time()
    dispatch = _Dispatch(study, client, plan_task)
    try:
        dispatch.submit_all(todo)
        for chunk, table, timings in dispatch.finished_chunks():
            store.write(chunk, table)
            run.computed_chunks += 1
            run.timings.extend(timings)
            done += table.num_rows
            progress.count(done, study.tasks, 'tasks')
    finally:
        dispatch.cancel()
    run.split_chunks = dispatch.split
    run.finished = time.time()
    return run


class _Dispatch:
    """Chunks in flight: whole, or split into one-task pieces after killing workers."""

    def __init__(self, study: Study, client: Client, plan_task):
        self.study = study
        self.client = client
        self.plan_task = plan_task
        # A fresh key per run: a run resumed on the same cluster must not meet the futures
        # of the run it resumes, which the scheduler may still be cancelling.
        self.prefix = f'ftplan-study-{study.digest()[:12]}-{uuid.uuid4().hex[:8]}'
        self.in_flight = {}            # future -> (chunk, tasks)
        self.pieces = {}               # chunk -> [tables or None per task] while split
        self.timings = {}              # chunk -> [ChunkTiming] while split
        self.split = 0
        self.queue = as_completed()

    def submit_all(self, chunks: list[int]) -> None:
        """Send every chunk out (Dask's scheduler queues what the workers cannot take yet)."""
        for chunk in chunks:
            self._submit(chunk, list(self.study.chunk_tasks(chunk)), f'chunk-{chunk}')

    def finished_chunks(self):
        """Yield (chunk, table, timings) as whole chunks finish."""
        for future in self.queue:
            chunk, tasks = self.in_flight.pop(future)
            try:
                outcome = self._outcome(future, chunk, tasks)
            finally:
                future.release()
            if outcome is None:
                continue  # split into pieces
            whole = self._collect(chunk, tasks, *outcome)
            if whole is not None:
                yield (chunk, *whole)

    def cancel(self) -> None:
        """Cancel whatever is still in flight (an interrupted or failed study)."""
        if self.in_flight:
            self.client.cancel(list(self.in_flight))
            self.in_flight.clear()

    def _submit(self, chunk: int, tasks: list[int], name: str) -> None:
        future = self.client.submit(run_chunk, self.study, tasks, self.plan_task,
                                    key=f'{self.prefix}-{name}', pure=False)
        self.in_flight[future] = (chunk, tasks)
        self.queue.add(future)

    def _outcome(self, future, chunk: int, tasks: list[int]):
        """Return (table, timings) of a finished future; None when it was split instead."""
        try:
            result: ChunkResult = future.result()
        except KilledWorker as error:
            if len(tasks) > 1:
                self._split(chunk, tasks)
                return None
            row = error_row(self.study, tasks[0], 'KilledWorker: the worker died every time '
                            f'it planned this task ({error})')
            return rows_to_table([row], self.study.dim), []
        except Exception as error:
            raise StudyError(f'chunk {chunk} failed on the workers: '
                             f'{type(error).__name__}: {error}') from error
        return result.table, [ChunkTiming(chunk, len(tasks), result.worker, result.started,
                                          result.finished)]

    def _split(self, chunk: int, tasks: list[int]) -> None:
        self.split += 1
        self.pieces[chunk] = [None] * len(tasks)
        self.timings[chunk] = []
        for index in tasks:
            self._submit(chunk, [index], f'chunk-{chunk}-task-{index}')

    def _collect(self, chunk: int, tasks: list[int], table, timing):
        """Return (table, timings) once every piece of `chunk` is in, else None."""
        if chunk not in self.pieces:
            return table, timing
        first = self.study.chunk_tasks(chunk).start
        self.pieces[chunk][tasks[0] - first] = table
        self.timings[chunk].extend(timing)
        if any(piece is None for piece in self.pieces[chunk]):
            return None
        tables = self.pieces.pop(chunk)
        return pa.concat_tables(tables), self.timings.pop(chunk)


def _describe_cluster(client: Client) -> str:
    workers = client.scheduler_info(n_workers=-1)['workers']
    threads = sum(w.get('nthreads', 0) for w in workers.values())
    return f'scheduler {client.scheduler.address}, {len(workers)} workers, {threads} threads'


class _Silent:
    def line(self, text: str) -> None:
        pass

    def begin(self, done: int = 0) -> None:
        pass

    def count(self, done: int, total: int, unit: str = '') -> None:
        pass
