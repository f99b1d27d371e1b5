"""Project rules that code review would otherwise have to catch."""

import pkgutil
import subprocess
import sys
from pathlib import Path

import ftplan_ros.bench
import ftplan_ros.core
import ftplan_ros.execution
import ftplan_ros.figures
import ftplan_ros.simulation
import ftplan_ros.study

REPO = Path(__file__).resolve().parents[2]


def test_ruff_is_clean():
    run = subprocess.run([sys.executable, '-m', 'ruff', 'check', 'ftplan_ros', 'ftplan_msgs_py',
                          'test', 'benchmarks', 'tools'], cwd=REPO, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr


def test_the_ros_free_packages_load_no_ros_module():
    """Import them for real: a ROS module pulled in by any import chain would show."""
    modules = ['ftplan_ros.cli']
    for package in (ftplan_ros.core, ftplan_ros.execution, ftplan_ros.simulation,
                    ftplan_ros.study, ftplan_ros.bench, ftplan_ros.figures):
        modules += [package.__name__] + [m.name for m in pkgutil.walk_packages(
            package.__path__, package.__name__ + '.')]
    # The plan workers' fork server imports these: no ROS threads in the processes it forks.
    modules += [f'ftplan_ros.nodes.plan_{name}' for name in ('pool', 'worker', 'jobs')]
    # A recording is written and read without ROS (only the recorder node subscribes).
    modules += [f'ftplan_ros.recording.{name}' for name in ('definitions', 'bag_writer',
                                                            'bag_reader')]
    code = ('import importlib, sys\n'
            f'for name in {modules!r}:\n'
            '    importlib.import_module(name)\n'
            'ros = ("rclpy", "rosidl_runtime_py")\n'
            'print(sorted(m for m in sys.modules if m.split(".")[0] in ros))\n')
    run = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                         cwd=REPO, timeout=300)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == '[]'
    assert len(modules) > 60, f'found only {len(modules)} modules: is the walk broken?'
