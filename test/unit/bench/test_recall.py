"""The recall benchmark's tables (`ftplan bench`), with and without the grid baseline."""

import json
import subprocess
import sys

from ftplan_ros.bench.recall import RecallRun, summarize


def _run(index, existence, cold_s, grid_s=None, grid_feasible=None):
    feasible = existence == 'yes'
    return RecallRun('random', index, 3, existence, 0.2, feasible,
                     'paper_surface' if feasible else '', cold_s, cold_s, False, False, '',
                     {}, grid_s, grid_feasible)


def test_the_grid_baseline_adds_its_p50_its_ratio_and_its_answers():
    runs = [_run(0, 'yes', 0.010, 1.4, True), _run(1, 'yes', 0.020, 1.6, False),
            _run(2, 'no', 0.030, 1.5, True), _run(3, 'unsure', 0.015, 1.3, False)]
    text = summarize(runs, 64, grid_baseline=180)
    line = next(row for row in text.splitlines() if row.startswith('all: all'))
    # cold p50 17.5 ms, reference p50 200 ms, grid p50 1450 ms
    assert line.split()[-4:] == ['200', '11x', '1450', '83x']
    assert 'grid 180^3 p50' in text
    assert ('a plan exists on 1 of 2 YES scenes, on 1 of 1 NO scenes and on 0 of 1 UNSURE '
            'scenes') in text


def test_a_planner_slower_than_the_reference_gets_a_ratio_below_one_not_zero():
    text = summarize([_run(0, 'yes', 8.0), _run(1, 'no', 12.0)], 64)  # reference: 0.2 s
    assert next(row for row in text.splitlines()
                if row.startswith('all: all')).split()[-1] == '0.02x'


def test_without_the_grid_baseline_the_table_has_no_such_column():
    text = summarize([_run(0, 'yes', 0.010), _run(1, 'no', 0.040)], 64)
    assert 'grid/cold' not in text and 'baseline' not in text
    assert next(row for row in text.splitlines()
                if row.startswith('all: all')).split()[-1] == '8.0x'


def test_the_command_runs_the_grid_baseline_on_every_scene(tmp_path):
    out = tmp_path / 'recall.json'
    run = subprocess.run([sys.executable, '-m', 'ftplan_ros.cli', 'bench', '--scenes', '1',
                          '--seed', '3', '--cells', '48', '--crowded-cells', '32',
                          '--grid-baseline', '24', '--json', str(out)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert 'grid 24^3 p50' in run.stdout
    runs = json.loads(out.read_text())
    assert len(runs) == 2
    assert all(r['grid_baseline_s'] > 0 and isinstance(r['grid_baseline_feasible'], bool)
               for r in runs)
