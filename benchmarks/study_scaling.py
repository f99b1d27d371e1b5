"""Scale `ftplan study` over Dask workers, and kill its driver mid-study, in one run.

    .venv/bin/python benchmarks/study_scaling.py [--tasks 2000] [--chunk 100] [--kill-at 0.35]

1. Scaling. The planar sweep of config/studies/obstacle_sweep.yaml cut to `--tasks` tasks
   (the paper's 3R arm, random start and goal, 0-10 random disks) runs on a LocalCluster
   of 1 worker, then of 2 (the command's own cluster, `study.open_client`), each into a
   fresh folder. Per run: wall time (first chunk submitted -> last chunk written), the
   speedup, how busy the workers were (time inside chunks / workers x wall), the cost
   per task (time inside chunks / tasks), and the scheduling overhead per task: the
   time each worker waited for its first chunk and between chunks, summed, over the
   tasks. The same study with a no-op task function (it only enumerates the task and
   makes its row) gives the whole per-task cost of Dask, Parquet and the driver.
   The two runs' results must agree row for row (every column but plan_time_s).
2. Kill and resume. `ftplan study ... --workers 2` runs in a child process; once
   `--kill-at` of its chunks are written, the driver gets SIGKILL. Its workers must go
   away on their own; then the same command runs again to the end. The results must
   hold every task exactly once and equal the uninterrupted 2-worker run's.
3. A projection, from the measured overhead, of a 100,000-task sweep on 64 workers.

Times are from this machine and this run (other work on the host slows them); compare
them with each other.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import psutil
import yaml

from ftplan_ros.progress import Progress
from ftplan_ros.study import ResultStore, load_study, open_client, run_study
from ftplan_ros.study.tasks import task_inputs

REPO = Path(__file__).resolve().parents[1]
SWEEP = REPO / 'config' / 'studies' / 'obstacle_sweep.yaml'
COMPARED = ['task', 'start_x', 'start_y', 'goal_x', 'goal_y', 'random_obstacles',
            'obstacle_centers', 'obstacle_radii', 'feasible', 'outcome', 'reason', 'theta_s',
            'min_clearance', 'method', 'error']


def inputs_only(study, index):
    """A no-op task: the row of the task's inputs, nothing planned."""
    return task_inputs(study, study.task(index))


def write_spec(folder: Path, tasks: int, chunk: int) -> Path:
    """The obstacle sweep, cut to `tasks` tasks of `chunk` per chunk, as a spec file.

    Only the paper's method plans: the scaling is Dask's, and the recovery sheets would
    triple the run for the same answer.
    """
    data = yaml.safe_load(SWEEP.read_text())
    data['scene'] = str((SWEEP.parent / data['scene']).resolve())
    data['vary']['random']['tasks'] = tasks
    data['chunk'] = chunk
    data['planner']['methods'] = ['paper_surface']
    spec = folder / 'scaling.yaml'
    spec.write_text(yaml.safe_dump(data))
    return spec


def measure(spec: Path, out: Path, workers: int, plan_task=None) -> dict:
    """Run the study on a new LocalCluster of `workers`; return its measurements."""
    study = load_study(spec)
    started = time.perf_counter()
    with open_client(None, workers) as client:
        client.wait_for_workers(workers)
        cluster_s = time.perf_counter() - started
        run = run_study(study, ResultStore(out, study), client, Progress(), plan_task)
    wall = run.finished - run.started
    inside = sum(t.finished - t.started for t in run.timings)
    waits = 0.0
    for worker in {t.worker for t in run.timings}:
        mine = sorted((t for t in run.timings if t.worker == worker), key=lambda t: t.started)
        waits += mine[0].started - run.started
        waits += sum(b.started - a.finished for a, b in zip(mine, mine[1:], strict=False))
    table = ResultStore(out, study).read()
    return {'workers': workers, 'wall': wall, 'cluster': cluster_s, 'tasks': table.num_rows,
            'busy': inside / (workers * wall), 'cost': inside / study.tasks,
            'overhead': waits / study.tasks, 'rows': table.select(COMPARED).to_pylist(),
            'plan_time': np.nansum(np.array(table.column('plan_time_s').to_pylist(),
                                            dtype=float)) / study.tasks}


def kill_and_resume(spec: Path, out: Path, kill_at: float, chunks: int) -> dict:
    """SIGKILL the command's driver once `kill_at` of the chunks are in, then rerun it."""
    command = [sys.executable, '-m', 'ftplan_ros.cli', 'study', str(spec), '--out', str(out),
               '--workers', '2']
    log = out.parent / 'killed.log'
    with open(log, 'w') as sink:
        driver = subprocess.Popen(command, stdout=sink, stderr=sink, start_new_session=True)
    wanted = max(1, int(kill_at * chunks))
    while len(list(out.glob('chunk-*.parquet'))) < wanted:
        if driver.poll() is not None:
            raise SystemExit(f'the study ended before the kill; see {log}')
        time.sleep(0.05)
    children = psutil.Process(driver.pid).children(recursive=True)
    os.kill(driver.pid, signal.SIGKILL)
    driver.wait()
    at_kill = len(list(out.glob('chunk-*.parquet')))
    partial = len(list(out.glob('.chunk-*')))
    _, alive = psutil.wait_procs(children, timeout=60)
    for process in alive:          # our own children only, by pid
        process.kill()
    rerun = subprocess.run(command, capture_output=True, text=True, timeout=3600)
    if rerun.returncode != 0:
        raise SystemExit(f'the rerun failed:\n{rerun.stderr}')
    study = load_study(spec)
    table = ResultStore(out, study).read()
    tasks = table.column('task').to_pylist()
    computed = [line for line in rerun.stderr.splitlines() if 'computed' in line]
    return {'at_kill': at_kill, 'partial_files': partial, 'children': len(children),
            'orphans': len(alive), 'rerun': computed[-1].split('] ')[-1] if computed else '?',
            'rows': table.num_rows, 'unique': len(set(tasks)),
            'complete': tasks == list(range(study.tasks)),
            'table': table.select(COMPARED).to_pylist()}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--tasks', type=int, default=2000)
    parser.add_argument('--chunk', type=int, default=100)
    parser.add_argument('--kill-at', type=float, default=0.35,
                        help='fraction of the chunks written when the driver is killed')
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix='ftplan-study-scaling-') as folder:
        folder = Path(folder)
        spec = write_spec(folder, args.tasks, args.chunk)
        study = load_study(spec)
        print(f'study: {study.tasks} tasks ({SWEEP.name}: planar 3R, 0-10 random disks) in '
              f'{study.chunks} chunks of {study.chunk}; {os.cpu_count()} CPUs',
              file=sys.stderr)
        runs = [measure(spec, folder / f'workers-{n}', n) for n in (1, 2)]
        noop = measure(spec, folder / 'noop', 2, inputs_only)
        killed = kill_and_resume(spec, folder / 'killed', args.kill_at, study.chunks)
    print(report(study, runs, noop, killed))
    same = runs[0]['rows'] == runs[1]['rows'] == killed['table']
    ok = same and killed['complete'] and killed['unique'] == study.tasks
    return 0 if ok else 1


def report(study, runs, noop, killed) -> str:
    one, two = runs
    lines = [f'{"workers":>7}{"wall [s]":>10}{"tasks/s":>9}{"speedup":>9}{"busy":>7}'
             f'{"cost/task [ms]":>16}{"plan time/task [ms]":>21}{"overhead/task [ms]":>20}'
             f'{"overhead/cost":>15}{"cluster start [s]":>19}']
    for run in runs:
        lines.append(f'{run["workers"]:>7}{run["wall"]:>10.1f}{study.tasks / run["wall"]:>9.1f}'
                     f'{one["wall"] / run["wall"]:>8.2f}x{run["busy"]:>7.0%}'
                     f'{1e3 * run["cost"]:>16.1f}{1e3 * run["plan_time"]:>21.1f}'
                     f'{1e3 * run["overhead"]:>20.3f}{run["overhead"] / run["cost"]:>15.2%}'
                     f'{run["cluster"]:>19.1f}')
    noop_task = noop['wall'] / study.tasks
    orphans = killed['orphans']
    children = 'all exited by themselves' if not orphans else f'left {orphans} running (killed)'
    lines += [
        f'no-op tasks on 2 workers (Dask, rows, Parquet and the driver, nothing planned): '
        f'{1e3 * noop_task:.3f} ms/task of wall time ({noop_task / one["cost"]:.2%} of the '
        'cost of a planned task)',
        f'1 vs 2 workers, every column but plan_time_s: '
        f'{"identical" if one["rows"] == two["rows"] else "DIFFERENT"} ({len(one["rows"])} '
        f'and {len(two["rows"])} rows)',
        f'driver SIGKILLed with {killed["at_kill"]}/{study.chunks} chunks written '
        f'({killed["partial_files"]} half-written files); its {killed["children"]} child '
        f'processes {children}',
        f'rerun: {killed["rerun"]}; {killed["rows"]} rows, {killed["unique"]} distinct tasks, '
        f'every task exactly once: {"yes" if killed["complete"] else "NO"}; equal to the '
        f'uninterrupted run: {"yes" if killed["table"] == two["rows"] else "NO"}',
    ]
    per_task = two['overhead']
    lines.append('projection, 100,000 tasks on 64 workers (chunks of 200, measured overhead '
                 f'{1e3 * per_task:.2f} ms/task, tail of one chunk):')
    for label, cost in ((f'planar, measured {1e3 * one["cost"]:.0f} ms', one['cost']),
                        ('spatial at 0.2 s/task', 0.2), ('spatial at 1 s/task', 1.0)):
        hours = (100_000 * (cost + per_task) / 64 + 200 * cost) / 3600
        lines.append(f'  {label:<28} {hours:6.2f} h')
    return '\n'.join(lines)


if __name__ == '__main__':
    sys.exit(main())
