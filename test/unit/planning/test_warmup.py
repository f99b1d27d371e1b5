"""`load_kernels`: after it, plans compile no kernel, so the first plan of a kind does not wait.

numba compiles a kernel again for each new layout or write flag of its arrays: a plan that
passes a read-only or strided array where the warm-up passed a plain one waits for the
compiler (seconds, on a new machine) even though the warm-up ran.
"""

import json
import subprocess
import sys

from ftplan_testing import ROBOTS, SCENES

from ftplan_ros.core import load_kernels

# In a fresh interpreter: other tests of this process may have compiled any signature.
_PROBE = '''
import importlib, json, pkgutil, sys
import numba
import ftplan_ros.core as core
from ftplan_ros.core import load_kernels, plan, recover
from ftplan_ros.core.io.scene_file import load_scene

def signatures():
    found = {}
    for info in pkgutil.walk_packages(core.__path__, 'ftplan_ros.core.'):
        module = importlib.import_module(info.name)
        for name, kernel in vars(module).items():
            if (isinstance(kernel, numba.core.registry.CPUDispatcher)
                    and kernel.__module__ == module.__name__):
                found[f'{info.name}.{name}'] = {str(s) for s in kernel.signatures}
    return found

compiled = {}
for path in sys.argv[1:]:
    scene = load_scene(path)
    load_kernels(scene.robot)
    before = signatures()
    result = plan(scene)
    if result.feasible:  # as the executor calls it: a lock on the nominal path
        nominal = result.surface.nominal_path
        for joint in scene.tolerated_joints:
            recover(result.surface, nominal[len(nominal) // 2].copy(), joint)
    outcome = result.stats['method'] if result.feasible else result.reason[:60]
    new = {kernel: sorted(found - before.get(kernel, set()))
           for kernel, found in signatures().items() if found - before.get(kernel, set())}
    compiled[path.rsplit('/', 1)[-1]] = {'outcome': outcome, 'new': new}
print(json.dumps({'kernels': len(signatures()), 'scenes': compiled}))
'''


def test_plans_of_every_kind_compile_nothing_after_the_warm_up():
    scenes = ['fig3a', 'crowded_sheets_100', 'crowded_sheets_101', 'infeasible', 'arm4_spheres']
    run = subprocess.run([sys.executable, '-c', _PROBE, *(str(SCENES / f'{name}.yaml')
                                                          for name in scenes)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    found = json.loads(run.stdout)
    assert found['kernels'] >= 40, f'the walk found {found["kernels"]} kernels: is it broken?'
    compiled = found['scenes']
    outcomes = {name: found['outcome'] for name, found in compiled.items()}
    assert outcomes['fig3a.yaml'] == 'paper_surface'
    assert outcomes['crowded_sheets_100.yaml'] == 'recovery_sheets'
    assert outcomes['infeasible.yaml'].startswith('no failure-tolerant plan exists')
    assert {name: found['new'] for name, found in compiled.items() if found['new']} == {}


def test_a_robot_is_warmed_once_for_each_task_kind(monkeypatch):
    """A robot of a thousand shapes took 9 s each time: the nodes warm it off their executor,
    then their own call must return at once."""
    from ftplan_ros.core.io.scene_file import parse_scene
    from ftplan_ros.core.planning import warmup

    def panda():
        return parse_scene({'robot': 'panda.yaml'}, directory=ROBOTS).robot
    robot = panda()
    load_kernels(robot)
    runs = []
    monkeypatch.setattr(warmup, '_run_kernels', runs.append)
    load_kernels(robot)
    load_kernels(robot.with_task_kind(robot.task_kind))  # the same model for the same kind
    assert runs == []
    other_kind, other_model = robot.with_task_kind('position'), panda()
    load_kernels(other_kind)
    load_kernels(other_model)
    assert runs == [other_kind, other_model]
