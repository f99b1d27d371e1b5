import ast
import json
import os
import pkgutil
import subprocess
import sys
from pathlib import Path

# A submodule, not the package: `python -m pytest` from the repository root can shadow the
# package itself with the distribution folder ftplan_msgs_py/ (see the subprocess below).
import ftplan_msgs_py.stamps

PACKAGE_DIR = Path(ftplan_msgs_py.stamps.__file__).parent
MODULES = sorted(f'ftplan_msgs_py.{m.name}' for m in pkgutil.iter_modules([str(PACKAGE_DIR)]))
ALLOWED_TOP_LEVEL = {
    'ftplan_msgs_py', 'numpy', 'builtin_interfaces', 'diagnostic_msgs', 'geometry_msgs',
    'nav_msgs', 'sensor_msgs', 'std_msgs', 'trajectory_msgs', 'visualization_msgs',
} | set(sys.stdlib_module_names)

PROBE = '''
import importlib, json, sys
modules = [importlib.import_module(name) for name in sys.argv[1:]]
package = importlib.import_module('ftplan_msgs_py')
print(json.dumps({
    'loaded': sorted(m for m in ('rclpy', 'ftplan_ros') if m in sys.modules),
    'package_file': package.__file__,
    'missing_exports': [n for n in package.__all__ if not hasattr(package, n)],
    'exports': len(package.__all__),
}))
'''


def run_probe(tmp_path):
    # Run outside the repository root so the installed package, not the folder, is found.
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join(filter(None, [str(PACKAGE_DIR.parent),
                                                      env.get('PYTHONPATH')]))
    result = subprocess.run([sys.executable, '-c', PROBE, *MODULES], cwd=tmp_path, env=env,
                            capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


def test_every_module_is_found():
    assert {'ftplan_msgs_py.joint_state', 'ftplan_msgs_py.plan_markers'} <= set(MODULES)


def test_importing_every_module_loads_neither_rclpy_nor_ftplan_ros(tmp_path):
    assert run_probe(tmp_path)['loaded'] == []


def test_package_re_exports_its_whole_public_api(tmp_path):
    probe = run_probe(tmp_path)
    assert Path(probe['package_file']) == PACKAGE_DIR / '__init__.py'
    assert probe['missing_exports'] == []
    assert probe['exports'] > 20


def test_modules_import_only_numpy_stdlib_and_message_packages():
    for path in PACKAGE_DIR.glob('*.py'):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                roots = {alias.name.split('.')[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom):
                roots = {(node.module or '').split('.')[0]} if node.level == 0 else set()
            else:
                continue
            assert roots <= ALLOWED_TOP_LEVEL, f'{path.name} imports {roots - ALLOWED_TOP_LEVEL}'
