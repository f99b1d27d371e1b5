"""`ftplan study` (study/command.py): bad specs and schedulers refused in one line; resuming."""

import socket
import subprocess
import sys
import threading

import pytest
import yaml
from ftplan_testing import SCENES

from ftplan_ros.study import ResultStore, load_study, run_study
from ftplan_ros.study.results import OUTCOMES

from .interrupt import Interrupt
from .specs import MAP, spec_with


def test_the_command_resumes_a_study_on_a_running_scheduler(client, tmp_path):
    spec = tmp_path / 'map.yaml'
    spec.write_text(f'scene: {SCENES / "fig3a.yaml"}\nvary: {{start: {{x: [0.5, 2.5, 3], '
                    'y: [-0.5, 0.5, 2]}}\nchunk: 2\n')
    out = tmp_path / 'out'
    study = load_study(spec)
    with pytest.raises(KeyboardInterrupt):                   # a first run, stopped after 1 chunk
        run_study(study, ResultStore(out, study), client, Interrupt(chunks=1))
    command = [sys.executable, '-m', 'ftplan_ros.cli', 'study', spec, '--out', out,
               '--scheduler', client.scheduler.address]
    run = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert 'computed 2 chunks, skipped 1 found in the folder' in run.stderr
    assert '6/6 tasks' in run.stderr and 'tasks/s' in run.stderr
    assert 'study map: map of 6 tasks (6 in the results)' in run.stdout
    outcomes = ResultStore(out, study).read().column('outcome').to_pylist()
    for name in OUTCOMES:
        assert f'{name:<24}{outcomes.count(name):>8}' in run.stdout
    assert f'wrote {out / "map.png"}' in run.stdout and (out / 'map.png').stat().st_size > 10_000


def test_the_cli_rejects_a_bad_spec_in_one_line_before_starting_a_cluster(tmp_path):
    spec = tmp_path / 'spec.yaml'
    spec.write_text(yaml.safe_dump(spec_with(MAP, ('scene',), str(SCENES / 'fig3a.yaml')) |
                                   {'chunk': -5}))
    for extra, field in (((), 'chunk:'), (('--workers', '0'), '--workers:'),
                         (('--workers', '100000'), '--workers:'),
                         (('--workers', '2', '--scheduler', 'tcp://127.0.0.1:1'), '--workers:')):
        run = subprocess.run([sys.executable, '-m', 'ftplan_ros.cli', 'study', spec, '--out',
                              tmp_path / 'out', *extra], capture_output=True, text=True,
                             timeout=120)
        assert run.returncode == 2, run.stderr
        lines = run.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(f'ftplan: error: {field}'), run.stderr
    assert not (tmp_path / 'out').exists()
    spec.write_text('scene: [unclosed\n')
    run = subprocess.run([sys.executable, '-m', 'ftplan_ros.cli', 'study', spec, '--out',
                          tmp_path / 'out'], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and 'malformed YAML at line' in run.stderr


@pytest.mark.parametrize('address', ['tls://127.0.0.1:1'])  # a TypeError in Dask
def test_a_scheduler_that_cannot_be_reached_is_one_line_naming_the_flag(tmp_path, address):
    spec = tmp_path / 'spec.yaml'
    spec.write_text(yaml.safe_dump(spec_with(MAP, ('scene',), str(SCENES / 'fig3a.yaml'))))
    run = subprocess.run([sys.executable, '-m', 'ftplan_ros.cli', 'study', spec, '--out',
                          tmp_path / 'out', '--scheduler', address], capture_output=True,
                         text=True, timeout=120)
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1, run.stderr
    assert lines[0].startswith('ftplan: error: --scheduler: cannot connect'), run.stderr


def test_a_server_that_accepts_but_never_answers_is_given_up_naming_the_flag(tmp_path):
    """Issue 11's note: Dask's handshake has no deadline, so this hung the study for good."""
    server = socket.create_server(('127.0.0.1', 0))
    accepted = []
    threading.Thread(target=lambda: accepted.append(server.accept()), daemon=True).start()
    spec = tmp_path / 'spec.yaml'
    spec.write_text(yaml.safe_dump(spec_with(MAP, ('scene',), str(SCENES / 'fig3a.yaml'))))
    with server:
        run = subprocess.run([sys.executable, '-m', 'ftplan_ros.cli', 'study', spec, '--out',
                              tmp_path / 'out', '--scheduler',
                              f'tcp://127.0.0.1:{server.getsockname()[1]}'],
                             capture_output=True, text=True, timeout=120)
    lines = run.stderr.strip().splitlines()
    assert accepted and run.returncode == 2 and len(lines) == 1, run.stderr
    assert lines[0].startswith('ftplan: error: --scheduler: cannot connect') and \
        'no Dask scheduler answered' in lines[0], run.stderr
