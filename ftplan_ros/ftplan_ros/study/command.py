"""`ftplan study SPEC.yaml --out DIR [--scheduler ADDRESS] [--workers N]`.

Validates the spec and the folder before any cluster starts, runs the unfinished chunks on
an embedded LocalCluster (one single-threaded worker process per CPU unless `--workers`)
or on the cluster whose scheduler is at `--scheduler`, then prints the summary table and
draws the study's figure into DIR (`map.png` or `sweep.png`). Exit codes: 0 the study is
complete (tasks that raised are error rows, counted in the summary), 1 the workers could
not run it, 2 bad input, 130 interrupted; what was written stays, and the same command
resumes.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import threading
from pathlib import Path

import dask
from distributed import Client, LocalCluster

from ..core import InputError
from .results import ResultStore
from .runner import StudyError, run_study
from .spec import Study, load_study
from .summary import summarize

CONNECT_TIMEOUT_S = 20.0  # [s] Dask's deadline for a connection to the scheduler
HANDSHAKE_SLACK_S = 5.0   # [s] then how long the handshake may take before we give up


def run_study_command(spec: Path, out: Path, scheduler: str | None, workers: int | None,
                      progress) -> int:
    """Run the `study` subcommand; return its exit code (InputError propagates: exit 2)."""
    if scheduler is not None and workers is not None:
        raise InputError('--workers', 'sizes the local cluster: leave it out with --scheduler')
    if workers is not None and workers < 1:
        raise InputError('--workers', f'must be at least 1, got {workers}')
    most = 4 * (os.cpu_count() or 1)
    if workers is not None and workers > most:
        raise InputError('--workers', f'{workers} worker processes on {os.cpu_count()} CPUs: '
                         f'at most {most} here; use --scheduler for a cluster')
    study = load_study(spec)
    store = ResultStore(out, study)
    store.open()
    if len(store.finished_chunks()) < study.chunks:
        try:
            with open_client(scheduler, workers) as client:
                run = run_study(study, store, client, progress)
        except KeyboardInterrupt:
            print(f'ftplan: interrupted; {len(store.finished_chunks())} of {study.chunks} '
                  'chunks are written: run the same command to resume', file=sys.stderr)
            return 130
        except StudyError as error:
            print(f'ftplan: error: {error}', file=sys.stderr)
            return 1
        progress.line(f'computed {run.computed_chunks} chunks, skipped {run.skipped_chunks} '
                      'found in the folder' +
                      (f', split {run.split_chunks} after their workers died'
                       if run.split_chunks else ''))
    table = store.read()
    print(summarize(study, table))
    try:
        print(f'wrote {draw_study(study, table, out)}')
    except ValueError as error:  # a map over 3-D positions: no figure for it yet
        print(f'ftplan: no figure: {error}', file=sys.stderr)
    return 0


@contextlib.contextmanager
def open_client(scheduler: str | None, workers: int | None):
    """Open a client of the cluster at `scheduler`, or of a new LocalCluster of `workers`."""
    if scheduler is not None:
        with _connect(scheduler) as client:
            yield client
        return
    count = workers or (len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity')
                        else os.cpu_count() or 1)
    # One thread per worker: plans hold the GIL, so processes, not threads, run in parallel.
    # A worker holds one chunk at a time (saturation 1.0; Dask's default 1.1 queues a second
    # one behind it, which can leave another worker idle at the end). The scheduler and
    # nannies live in this process: keep their start-up chatter quiet.
    with dask.config.set({'distributed.scheduler.worker-saturation': 1.0}), \
            _logger_level('distributed', logging.WARNING), \
            LocalCluster(n_workers=count, threads_per_worker=1, processes=True,
                         dashboard_address=None, silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as client:
        yield client


def _connect(scheduler: str) -> Client:
    """Return a client of the scheduler at `scheduler`, or raise InputError naming the flag.

    Dask waits for the server's side of its handshake without a deadline, so a server
    that accepts the connection but never answers would hang the study: the client is
    made in a daemon thread that is given up after CONNECT_TIMEOUT_S and a little more.
    """
    made: dict = {}
    lock = threading.Lock()

    def connect() -> None:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT_S)
        except BaseException as error:  # noqa: BLE001 - whatever fails here, the address is bad
            made['error'] = error
            return
        with lock:
            if made.get('abandoned'):  # too late: nobody will close it but us
                client.close()
            else:
                made['client'] = client

    thread = threading.Thread(target=connect, name='ftplan-connect', daemon=True)
    thread.start()
    thread.join(CONNECT_TIMEOUT_S + HANDSHAKE_SLACK_S)
    with lock:
        if 'client' in made:
            return made['client']
        made['abandoned'] = True
    error = made.get('error')
    why = f'{type(error).__name__}: {error}' if error is not None else \
        f'no Dask scheduler answered within {CONNECT_TIMEOUT_S + HANDSHAKE_SLACK_S:.0f} s'
    raise InputError('--scheduler', f'cannot connect to {scheduler}: {why}')


@contextlib.contextmanager
def _logger_level(name: str, level: int):
    logger = logging.getLogger(name)
    old = logger.level
    logger.setLevel(max(level, old))
    try:
        yield
    finally:
        logger.setLevel(old)


def draw_study(study: Study, table, out: Path) -> Path:
    """Write the study's figure into `out`: map.png for a map, sweep.png for a sweep."""
    from ..figures import save_figure
    from .figures import map_figure, sweep_figure
    if study.kind == 'map':
        return save_figure(map_figure(study, table), Path(out) / 'map.png')
    return save_figure(sweep_figure(study, table), Path(out) / 'sweep.png')
