"""The `ftplan` command as users run it: outputs, files and exit codes."""

import io
import json

import pytest
from descriptions import CYCLE_JOINT, panda_with
from ftplan_testing import SCENES, ftplan, one_line_error

from ftplan_ros.cli import Progress


def test_plan_writes_the_contract_json(tmp_path):
    out = tmp_path / 'plan.json'
    run = ftplan('plan', SCENES / 'fig3a.yaml', '--json', out)
    assert run.returncode == 0, run.stderr
    assert 'feasible: theta_s = [' in run.stdout
    assert 'H3 (joint3) hit on M_g^F' in run.stdout
    assert 'tracing self-motion manifolds' in run.stderr  # the progress lines
    data = json.loads(out.read_text())
    assert data['feasible'] is True
    assert data['joint_names'] == ['joint1', 'joint2', 'joint3']
    assert len(data['theta_s']) == 3 and len(data['failure_plane_hits']) == 3
    paths = data['failure_surface']['paths']
    assert data['nominal_path'] == paths[data['failure_surface']['nominal']]
    assert set(data['hypercube']) == {'lower', 'upper'}
    assert data['stats']['plan_time_s'] > 0


def test_a_sheets_plan_names_its_grid():
    """crowded_sheets_101 plans on the 128^3 classes pooled to 64^3; the summary says so."""
    run = ftplan('plan', SCENES / 'crowded_sheets_101.yaml')
    assert run.returncode == 0, run.stderr
    assert 'method recovery_sheets' in run.stdout
    assert 'failure-tolerant set on a 64^3 joint grid pooled from 128^3' in run.stdout


def test_infeasible_plan_exits_1_with_the_reason(tmp_path):
    out = tmp_path / 'plan.json'
    run = ftplan('plan', SCENES / 'infeasible.yaml', '--json', out)
    assert run.returncode == 1
    assert 'no failure-tolerant plan: no failure-tolerant plan exists (proved' in run.stdout
    assert 'no candidate θ_s passes the necessary condition' in run.stdout
    data = json.loads(out.read_text())
    assert data['feasible'] is False and 'necessary condition' in data['reason']


def test_drill_prints_a_summary_and_draws(tmp_path):
    png = tmp_path / 'drill.png'
    run = ftplan('drill', SCENES / 'fig3c.yaml', '--trials', 60, '--seed', 2, '--png', png)
    assert run.returncode == 0, run.stderr
    assert '60/60 trials reached the goal without collision' in run.stdout
    assert run.stdout.count('joint') >= 4
    assert png.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'


def test_figure_writes_both_pictures(tmp_path):
    run = ftplan('figure', SCENES / 'fig3b.yaml', '--out', tmp_path)
    assert run.returncode == 0, run.stderr
    for name in ('fig3b_workspace.png', 'fig3b_joint_space.png'):
        assert (tmp_path / name).stat().st_size > 10_000


def test_plan_png(tmp_path):
    png = tmp_path / 'sub' / 'plan.png'
    assert ftplan('plan', SCENES / 'fig3b.yaml', '--png', png).returncode == 0
    assert png.read_bytes()[:4] == b'\x89PNG'


BAD = {
    'malformed.yaml': ('robot: {type: planar, link_lengths: [1, 1\n', 'malformed YAML at line'),
    'unknown.yaml': ('robot: {type: planar, link_lengths: [1, 1, 1], colour: red}\n',
                     'robot.colour: unknown key'),
    'nan.yaml': ('robot: {type: planar, link_lengths: [1, .nan, 1]}\n'
                 'task: {start: [2, 0], goal: [1, 0]}\n', r'robot.link_lengths[1]: must be finite'),
    'negative.yaml': ('robot: {type: planar, link_lengths: [1, -1, 1]}\n',
                      'robot.link_lengths[1]: must be > 0'),
    'radius.yaml': ('robot: {type: planar, link_lengths: [1, 1, 1]}\n'
                    'obstacles: [{type: sphere, center: [1, 1], radius: 0}]\n',
                    'obstacles[0].radius: must be > 0'),
    'reach.yaml': ('robot: {type: planar, link_lengths: [1, 1, 1]}\n'
                   'task: {start: [2, 0], goal: [4, 0]}\n', 'task.goal: [4.0, 0.0] is out of'),
    'same.yaml': ('robot: {type: planar, link_lengths: [1, 1, 1]}\n'
                  'task: {start: [2, 0], goal: [2, 0]}\n', 'task.goal: equals task.start'),
    'rigid.yaml': ('robot: {type: planar, link_lengths: [1, 1]}\n'
                   'task: {start: [1.5, 0], goal: [0.5, 0.5]}\n', 'no redundancy'),
    'base.yaml': ('robot: {type: planar, link_lengths: [1, 1, 1]}\n'
                  'obstacles: [{type: sphere, center: [0.1, 0], radius: 0.3}]\n'
                  'task: {start: [2, 0], goal: [1, 0]}\n', 'obstacles[0]: covers the robot base'),
    'notask.yaml': ('robot: {type: planar, link_lengths: [1, 1, 1]}\n', 'task: is missing'),
}


@pytest.mark.parametrize('name', sorted(BAD))
def test_bad_input_is_one_line_and_exit_2(tmp_path, name):
    text, message = BAD[name]
    (tmp_path / name).write_text(text)
    run = ftplan('plan', tmp_path / name)
    assert run.returncode == 2
    assert message in run.stderr
    assert 'Traceback' not in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1, run.stderr


def test_missing_file_and_bad_arguments_exit_2(tmp_path):
    run = ftplan('plan', tmp_path / 'nope.yaml')
    assert run.returncode == 2 and 'cannot read nope.yaml (no such file)' in run.stderr
    run = ftplan('drill', SCENES / 'fig3a.yaml', '--trials', 0)
    assert run.returncode == 2 and '--trials: must be at least 1' in run.stderr
    run = ftplan('plan', SCENES / 'fig3a.yaml', '--margin', 'nan')
    assert run.returncode == 2 and '--margin' in run.stderr
    assert ftplan('launch').returncode == 2  # argparse: unknown command


@pytest.mark.parametrize('extra, message', [
    pytest.param(CYCLE_JOINT, "robot.file: link panda_link2 has two parents (joints "
                 "'panda_joint2' and 'cyc')", id='cycle'),
    pytest.param('<link name="pedestal"/>', "robot.file: has 2 root links, 'panda_link0' and "
                 "'pedestal'", id='two-roots'),
])
def test_a_urdf_that_is_no_tree_is_one_line_and_exit_2(tmp_path, extra, message):
    """Pinocchio crashed on the cycle (SIGSEGV, no output) before it was checked."""
    (tmp_path / 'robot.urdf').write_text(panda_with(extra))
    scene = tmp_path / 'scene.yaml'
    scene.write_text('robot: {type: urdf, file: robot.urdf, base_link: panda_link0, '
                     'tip_link: panda_hand_tcp}\n'
                     'task: {start: [0.5, -0.3, 0.4], goal: [0.4, 0.3, 0.5]}\n')
    run = ftplan('plan', scene)
    assert run.returncode == 2, run.stderr
    assert len(run.stderr.strip().splitlines()) == 1, run.stderr
    assert run.stderr.startswith(f'ftplan: error: {message}'), run.stderr
# Input that once crashed or got through: one line of error, before any work ----------------

def test_a_scene_that_is_not_utf8_is_one_line_of_error(tmp_path):
    scene = tmp_path / 'latin1.yaml'
    scene.write_bytes('robot: {type: planar}  # café\n'.encode('latin-1'))
    one_line_error(ftplan('plan', scene), 'UTF-8')


def test_a_number_too_big_for_a_float_is_one_line_of_error(tmp_path):
    scene = tmp_path / 'big.yaml'
    scene.write_text(f'robot: {{type: planar, link_lengths: [1.0, 1{"0" * 400}, 1.0]}}\n')
    one_line_error(ftplan('plan', scene), 'robot.link_lengths[1]')


@pytest.mark.parametrize('args, field', [
    (['plan', SCENES / 'fig3a.yaml', '--png', 'figure.jpg'], '--png'),
    (['plan', SCENES / 'fig3a.yaml', '--seed', '-1'], '--seed'),
    (['drill', SCENES / 'fig3a.yaml', '--trials', '0'], '--trials'),
    (['bench', '--scenes', '0'], '--scenes'),
    (['bench', '--cells', '0'], '--cells'),
    (['bench', '--grid-baseline', '8'], '--grid-baseline'),
    (['bench', '--robot', 'panda', '--grid-baseline', '180'], '--grid-baseline'),
    (['bench', '--robot', 'iiwa14', '--cells', '64'], '--cells: sets the planar3r benchmark'),
    (['bench', '--robot', 'panda', '--crowded-cells', '64'], '--crowded-cells'),
])
def test_bad_flags_are_refused_before_any_work(tmp_path, args, field):
    out = tmp_path / 'plan.json'
    run = ftplan(*args, '--json', out) if args[0] == 'plan' else ftplan(*args)
    one_line_error(run, field)
    assert 'tracing' not in run.stderr and not out.exists()


def test_the_plan_json_has_no_infinity_without_obstacles(tmp_path):
    out = tmp_path / 'plan.json'
    assert ftplan('plan', SCENES / 'paper_a_free.yaml', '--json', out).returncode == 0

    def refuse(constant):
        raise AssertionError(f'{constant} is not JSON')
    data = json.loads(out.read_text(), parse_constant=refuse)
    assert data['feasible'] is True
    assert data['stats']['min_clearance_m'] is None  # infinite: no obstacle anywhere


def test_benchmark_sizes_that_cannot_fit_in_memory_are_refused():
    one_line_error(ftplan('bench', '--cells', 100000), '--cells: must be at most')


def test_progress_prints_rate_and_eta_at_most_once_a_second():
    now = [100.0]
    stream = io.StringIO()
    progress = Progress(stream, clock=lambda: now[0])
    progress.begin(200)                       # 200 done by an earlier run
    now[0] = 110.0
    progress.count(300, 1200, 'tasks')        # 100 in 10 s: 10/s, 900 left: 90 s
    now[0] = 110.5
    progress.count(305, 1200, 'tasks')        # within the second: quiet
    now[0] = 190.0
    progress.count(1200, 1200, 'tasks')       # the end always prints
    lines = stream.getvalue().splitlines()
    assert len(lines) == 2
    assert lines[0].endswith('300/1200 tasks, 10.0 tasks/s, ETA 90 s')
    assert lines[1].endswith('1200/1200 tasks, 11.1 tasks/s')


def test_replay_of_a_file_that_is_no_complete_recording_is_one_line_and_exit_2(tmp_path):
    """Issue 37: a file that is not MCAP, or one cut off, is refused naming the file.
    (Run outside the repository, whose package folders would hide ftplan_msgs_py.)"""
    text = tmp_path / 'notes.mcap'
    text.write_text('not a recording\n')
    run = ftplan('replay', text, '--png', tmp_path / 'x.png', cwd=tmp_path)
    one_line_error(run, 'notes.mcap: is not an MCAP file')
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(b'\x89MCAP0\r\n' + bytes(100))
    one_line_error(ftplan('replay', cut, cwd=tmp_path),
                   'cut.mcap: is not a complete MCAP recording')
    one_line_error(ftplan('replay', cut, '--png', tmp_path / 'x.jpg', cwd=tmp_path), '--png')
    assert not (tmp_path / 'x.png').exists()
