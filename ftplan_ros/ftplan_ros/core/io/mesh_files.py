"""Where a URDF's collision meshes are: `package://`, `file://` and paths, found as ROS does.

A mesh's `filename` is looked up in this order, and the first file that exists is used:

- `package://PKG/PATH`: `DIR/PKG/PATH` for each folder DIR of `mesh_dirs` (folders that
  hold packages); then `PREFIX/share/PKG/PATH` for each prefix of AMENT_PREFIX_PATH (ROS 2's
  install spaces); then the package named PKG in its package.xml under the folders of
  ROS_PACKAGE_PATH (ROS 1's rospack, which crawls them); last, an ancestor folder of the
  URDF named PKG (a URDF inside its package's source tree).
- `file:///ABS/PATH`: that absolute path.
- a path: as it is when absolute; else relative to the URDF's folder, then to each of
  `mesh_dirs`.

A mesh that is nowhere raises InputError naming its link, its URI and every place looked.
STL, OBJ and COLLADA files are read by Pinocchio (coal, through assimp), which leaves out
a COLLADA file's `<unit meter=...>`: it is multiplied into the mesh's `scale` here, as
RViz does, so a mesh drawn in millimetres comes out in metres. Visual meshes are left
alone: only collision geometry is loaded.
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ElementTree
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import replace
from pathlib import Path

from ..errors import InputError
from ..model.description_xml import serialize
from ..model.urdf_structure import UrdfDescription

# rospack's crawl of ROS_PACKAGE_PATH goes no deeper than this below each of its folders,
# and reads at most this many folders in all (a workspace holds a few hundred packages).
_CRAWL_DEPTH = 6
_CRAWL_FOLDERS = 20_000
_HEAD_BYTES = 64 * 1024  # a COLLADA file's <asset> and a package.xml's <name> are in these
_UNIT = re.compile(rb'<unit\b[^>]*\bmeter\s*=\s*["\']([^"\']+)["\']')
_PACKAGE_NAME = re.compile(rb'<name>\s*([^<\s]+)\s*</name>')
_SHOWN_PLACES = 6  # places named in a missing mesh's error
SMALLEST_UNIT, LARGEST_UNIT = 1e-6, 1e3  # [m] COLLADA units: micrometres to kilometres


def with_mesh_files(urdf: UrdfDescription, directory: Path | None = None,
                    mesh_dirs: Sequence[Path] = (), where: str = 'robot',
                    environ: Mapping[str, str] | None = None) -> UrdfDescription:
    """Return the URDF with every collision mesh's filename an absolute path (module docstring).

    `directory` is the URDF file's folder (None for a URDF from a topic); `environ` the
    environment to read AMENT_PREFIX_PATH and ROS_PACKAGE_PATH from (default: this
    process's). A COLLADA mesh's scale takes its file's unit. InputError `<where>.file`
    names a mesh that is nowhere, or a URI of another scheme.
    """
    root = ElementTree.fromstring(urdf.xml)
    finder = MeshFinder(directory, mesh_dirs, os.environ if environ is None else environ)
    changed = False
    for link in root.findall('link'):
        for mesh in link.findall('collision/geometry/mesh'):
            uri = mesh.get('filename')
            path = finder.find(uri, f'{where}.file', f'link {link.get("name")!r}')
            mesh.set('filename', str(path))
            unit = _unit(path, f'{where}.file', f'link {link.get("name")!r}')
            if unit != 1.0:
                scale = [float(v) for v in mesh.get('scale', '1 1 1').split()]
                mesh.set('scale', ' '.join(repr(v * unit) for v in scale))
            changed = True
    return replace(urdf, xml=serialize(root)) if changed else urdf


def _unit(path: Path, field: str, owner: str) -> float:
    """Return a mesh file's length unit [m]: a COLLADA file's, else 1."""
    if path.suffix.lower() != '.dae':
        return 1.0
    try:
        return collada_unit(path)
    except (OSError, ValueError) as error:
        raise InputError(field, f'{owner}: collision mesh {path.name}: {error}') from None


class MeshFinder:
    """Find mesh files by URI (see the module docstring) from one environment."""

    def __init__(self, directory: Path | None, mesh_dirs: Sequence[Path],
                 environ: Mapping[str, str]):
        self.directory = directory
        self.mesh_dirs = [Path(d) for d in mesh_dirs]
        self.ament_prefixes = _path_list(environ.get('AMENT_PREFIX_PATH', ''))
        self.ros_package_path = _path_list(environ.get('ROS_PACKAGE_PATH', ''))
        self._ros_packages: dict[str, Path] | None = None

    def find(self, uri: str, field: str, owner: str) -> Path:
        """Return the file a mesh URI names; InputError `field` naming `owner` if there is none."""
        looked = []
        for path in self.places(uri, field, owner):
            if path.is_file():
                return path.resolve()
            looked.append(path)
        raise InputError(field, f'{owner}: collision mesh {uri!r} was not found; '
                         f'{self._looked(uri, looked)}')

    def places(self, uri: str, field: str, owner: str) -> Iterator[Path]:
        """Yield the paths where `uri` may be, in the order they are tried."""
        if uri.startswith('package://'):
            package, _, inside = uri[len('package://'):].partition('/')
            if not package or not inside:
                raise InputError(field, f'{owner}: mesh {uri!r} names no package and file: '
                                 'write package://PACKAGE/PATH')
            yield from (root / inside for root in self._package_roots(package))
        elif uri.startswith('file://'):
            path = Path(uri[len('file://'):])
            if not path.is_absolute():
                raise InputError(field, f'{owner}: mesh {uri!r} is not an absolute file URI: '
                                 'write file:///ABSOLUTE/PATH')
            yield path
        elif '://' in uri:
            raise InputError(field, f'{owner}: mesh {uri!r} has a scheme ftplan does not '
                             'read: use package://, file:// or a path')
        elif Path(uri).is_absolute():
            yield Path(uri)
        else:
            folders = [self.directory] if self.directory is not None else []
            yield from (folder / uri for folder in folders + self.mesh_dirs)

    def _package_roots(self, package: str) -> Iterator[Path]:
        """Yield the folders a package may be in, in the module docstring's order."""
        yield from (folder / package for folder in self.mesh_dirs)
        yield from (prefix / 'share' / package for prefix in self.ament_prefixes)
        if package in self.ros_packages():
            yield self.ros_packages()[package]
        if self.directory is not None:
            here = Path(self.directory).resolve()
            yield from (folder for folder in (here, *here.parents) if folder.name == package)

    def ros_packages(self) -> dict[str, Path]:
        """Return the packages under ROS_PACKAGE_PATH by name, crawled once, as rospack does.

        A folder holding a package.xml is a package (named by its <name>) and is not
        searched further; hidden folders and those holding CATKIN_IGNORE are skipped; the
        first package of a name wins. The crawl stops _CRAWL_DEPTH folders down and after
        _CRAWL_FOLDERS folders.
        """
        if self._ros_packages is not None:
            return self._ros_packages
        self._ros_packages = {}
        queue = [(folder, 0) for folder in self.ros_package_path]
        for visited, (folder, depth) in enumerate(queue):
            if visited >= _CRAWL_FOLDERS:
                break
            if not folder.is_dir() or (folder / 'CATKIN_IGNORE').exists():
                continue
            if (folder / 'package.xml').is_file():
                name = _package_name(folder / 'package.xml')
                if name:
                    self._ros_packages.setdefault(name, folder)
                continue
            if depth < _CRAWL_DEPTH:
                queue.extend((child, depth + 1) for child in _subfolders(folder))
        return self._ros_packages

    def _looked(self, uri: str, looked: list[Path]) -> str:
        """Say where a missing mesh was looked for and how to make it found."""
        shown = ', '.join(str(p) for p in looked[:_SHOWN_PLACES])
        more = f' and {len(looked) - _SHOWN_PLACES} more' if len(looked) > _SHOWN_PLACES else ''
        where = f'looked in {shown}{more}' if looked else 'looked nowhere'
        if not uri.startswith('package://'):
            return f'{where}: give its path relative to the URDF, or its folder in robot.mesh_dirs'
        package = uri[len('package://'):].partition('/')[0]
        searched = (f'robot.mesh_dirs {[str(d) for d in self.mesh_dirs]}, AMENT_PREFIX_PATH '
                    f'{[str(p) for p in self.ament_prefixes]}, ROS_PACKAGE_PATH '
                    f'{[str(p) for p in self.ros_package_path]}')
        return (f'{where} (searched {searched}): put the folder holding {package!r} in '
                f'robot.mesh_dirs, or the install prefix of {package!r} in AMENT_PREFIX_PATH')


def collada_unit(path: Path) -> float:
    """Return a COLLADA file's length unit [m] (its <asset><unit meter=...>), 1.0 if none.

    ValueError for a unit that is not a number within [SMALLEST_UNIT, LARGEST_UNIT].
    """
    with open(path, 'rb') as file:
        match = _UNIT.search(file.read(_HEAD_BYTES))
    if match is None:
        return 1.0
    text = match.group(1).decode('utf-8', 'replace')
    try:
        unit = float(text)
    except ValueError:
        unit = float('nan')
    if not SMALLEST_UNIT <= unit <= LARGEST_UNIT:
        raise ValueError(f'its <unit meter="{text:.30}"> is not a length within '
                         f'[{SMALLEST_UNIT:g}, {LARGEST_UNIT:g}] m')
    return unit


def _package_name(manifest: Path) -> str:
    try:
        with open(manifest, 'rb') as file:
            match = _PACKAGE_NAME.search(file.read(_HEAD_BYTES))
    except OSError:
        return ''
    return match.group(1).decode('utf-8', 'replace') if match else ''


def _subfolders(folder: Path) -> list[Path]:
    try:
        return sorted(child for child in folder.iterdir()
                      if not child.name.startswith('.') and child.is_dir())
    except OSError:
        return []


def _path_list(value: str) -> list[Path]:
    return [Path(item) for item in value.split(os.pathsep) if item]
