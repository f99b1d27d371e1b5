"""The import layers of ftplan_ros, read from the source of every module, recursively.

core/ is layered along the data flow (core/__init__.py draws the map): a subpackage imports
only from the layers below it, never from one above, never from outside core/. Only the
ROS adapters (nodes/, bringup.py, plan_client.py) may import rclpy; the logic they adapt
(execution/, simulation/) imports no message type either, and nothing of the adapters. The
checks walk the files themselves, so that a module added in a new subpackage is checked
too, and each asserts that it found something to check.
"""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / 'ftplan_ros' / 'ftplan_ros'

# What each part of core/ may import (besides itself): the layers below it.
CORE_LAYERS = {
    'errors': set(),
    'validation': {'errors'},
    'model': {'errors', 'validation'},
    'collision': {'errors', 'validation', 'model'},
    'paper': {'errors', 'validation', 'model', 'collision'},
    'grid': {'errors', 'validation', 'model', 'collision', 'paper'},
    'planning': {'errors', 'validation', 'model', 'collision', 'paper', 'grid'},
    'io': {'errors', 'validation', 'model', 'collision'},
    '__init__': {'errors', 'validation', 'model', 'collision', 'paper', 'grid', 'planning',
                 'io'},
}
# Packages and modules of ftplan_ros that may import rclpy: the ROS adapters.
ROS_ADAPTERS = {'nodes', 'bringup', 'plan_client'}
ROS_PACKAGES = {'rclpy', 'rosidl_runtime_py'}
# The logic of the nodes, without ROS: what each may import of ftplan_ros besides itself.
ROS_FREE_LOGIC = {'execution': {'core'}, 'simulation': {'core', 'execution'}}


def module_name(path: Path) -> str:
    """Return the dotted name of a module file of ftplan_ros."""
    parts = list(path.relative_to(PACKAGE.parent).with_suffix('').parts)
    return '.'.join(parts[:-1] if parts[-1] == '__init__' else parts)


def imported_modules(path: Path) -> set[str]:
    """Return the modules (and names) a file imports anywhere in its code, as dotted names."""
    name = module_name(path)
    package = name if path.name == '__init__.py' else name.rpartition('.')[0]
    tree = ast.parse(path.read_text(), str(path))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split('.')
                base = base[:len(base) - (node.level - 1)]
                module = '.'.join(base + ([node.module] if node.module else []))
            else:
                module = node.module
            found.add(module)
            found.update(f'{module}.{alias.name}' for alias in node.names)
    return found


def modules_under(folder: Path) -> list[Path]:
    """Return every .py file below `folder`, recursively."""
    return sorted(folder.rglob('*.py'))


def core_part(module: str) -> str | None:
    """Return the layer of a module of ftplan_ros.core ('model', 'errors', ...), else None."""
    parts = module.split('.')
    if parts[:2] != ['ftplan_ros', 'core']:
        return None
    return parts[2] if len(parts) > 2 else '__init__'


def test_every_core_module_imports_only_from_its_own_layer_or_below():
    files = modules_under(PACKAGE / 'core')
    upward = []
    for path in files:
        layer = core_part(module_name(path))
        assert layer in CORE_LAYERS, f'{path}: {layer!r} is in no layer: add it to CORE_LAYERS'
        for imported in imported_modules(path):
            if imported.startswith('ftplan_ros') and not imported.startswith('ftplan_ros.core'):
                upward.append(f'{module_name(path)} imports {imported} (outside core)')
            target = core_part(imported)
            if target is not None and target != layer and target not in CORE_LAYERS[layer]:
                upward.append(f'{module_name(path)} ({layer}) imports {imported} ({target})')
    assert len(files) >= 40, f'found only {len(files)} core modules: is the walk broken?'
    assert {core_part(module_name(p)) for p in files} == set(CORE_LAYERS)
    assert not upward, '\n'.join(upward)


def test_only_the_ros_adapters_import_rclpy():
    files = modules_under(PACKAGE)
    offenders = []
    adapters = 0
    for path in files:
        top = path.relative_to(PACKAGE).with_suffix('').parts[0]
        ros = {m for m in imported_modules(path) if m.split('.')[0] in ROS_PACKAGES}
        if top in ROS_ADAPTERS:
            adapters += bool(ros)
        elif ros:
            offenders.append(f'{module_name(path)} imports {sorted(ros)}')
    assert len(files) >= 80, f'found only {len(files)} modules: is the walk broken?'
    assert adapters >= 5, 'the walk found almost no ROS adapter importing rclpy'
    assert not offenders, '\n'.join(offenders)


@pytest.mark.parametrize('package', sorted(ROS_FREE_LOGIC))
def test_the_logic_of_the_nodes_imports_no_ros_no_messages_and_no_adapter(package):
    files = modules_under(PACKAGE / package)
    allowed = {package} | ROS_FREE_LOGIC[package]
    offenders = []
    for path in files:
        for imported in imported_modules(path):
            top = imported.split('.')[0]
            if top in ROS_PACKAGES or top.endswith('_msgs') or top == 'ftplan_msgs_py':
                offenders.append(f'{module_name(path)} imports {imported}')
            elif top == 'ftplan_ros' and (imported.split('.') + [''])[1] not in allowed:
                offenders.append(f'{module_name(path)} imports {imported} (outside {allowed})')
    assert len(files) >= 5, f'found only {len(files)} modules in {package}/'
    assert not offenders, '\n'.join(offenders)


def import_graph() -> dict[str, set[str]]:
    """Return the imports between modules of ftplan_ros (module -> modules).

    Every import counts, inside functions and `if TYPE_CHECKING:` too: either would hide a
    cycle. An imported name resolves to the deepest module of ftplan_ros that holds it.
    """
    files = modules_under(PACKAGE)
    names = {module_name(path) for path in files}
    graph = {}
    for path in files:
        edges = set()
        for imported in imported_modules(path):
            while imported and imported not in names:
                imported = imported.rpartition('.')[0]
            if imported and imported != module_name(path):
                edges.add(imported)
        graph[module_name(path)] = edges
    return graph


def test_no_import_cycle_between_modules():
    graph = import_graph()
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    cycles = []

    def visit(module: str, path: list[str]) -> None:
        state[module] = 1
        for imported in sorted(graph[module]):
            if imported.startswith(module + '.'):  # a package importing its own modules
                continue
            if state.get(imported) == 1:
                cycles.append(' -> '.join(path[path.index(imported):] + [imported]))
            elif imported not in state:
                visit(imported, path + [imported])
        state[module] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module, [module])
    assert sum(len(edges) for edges in graph.values()) > 200, 'the graph has almost no edge'
    assert not cycles, '\n'.join(cycles)


@pytest.mark.parametrize('layer', sorted(set(CORE_LAYERS) - {'__init__', 'errors',
                                                                  'validation'}))
def test_each_core_subpackage_says_what_it_holds(layer):
    init = PACKAGE / 'core' / layer / '__init__.py'
    doc = ast.get_docstring(ast.parse(init.read_text()))
    assert doc and len(doc.split()) > 20, f'{init}: the docstring should draw its room'
