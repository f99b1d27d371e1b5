"""The cache folder (core/io/cache.py): where it is, whole entries, and what failures cost."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from ftplan_ros.core.io import cache as cache_module
from ftplan_ros.core.io.cache import cache_dir, entry_path, read_entry, write_entry


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache folder of the test's own."""
    monkeypatch.setenv('FTPLAN_CACHE_DIR', str(tmp_path / 'cache'))
    return tmp_path / 'cache'


def test_the_folder_is_ftplan_cache_dir_else_xdg_cache_home_else_dot_cache(tmp_path,
                                                                         monkeypatch):
    monkeypatch.setenv('HOME', str(tmp_path / 'home'))
    monkeypatch.delenv('XDG_CACHE_HOME', raising=False)
    monkeypatch.delenv('FTPLAN_CACHE_DIR', raising=False)
    assert cache_dir() == tmp_path / 'home' / '.cache' / 'ftplan'
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path / 'xdg'))
    assert cache_dir() == tmp_path / 'xdg' / 'ftplan'
    monkeypatch.setenv('FTPLAN_CACHE_DIR', str(tmp_path / 'mine'))
    assert cache_dir() == tmp_path / 'mine'


def test_an_entry_reads_back_as_written(cache):
    assert read_entry('things', 'k1') is None
    assert write_entry('things', 'k1', {'a': [1, 2]}) == cache / 'things' / 'k1.json'
    assert read_entry('things', 'k1') == {'a': [1, 2]}
    assert [p.name for p in (cache / 'things').iterdir()] == ['k1.json']


@pytest.mark.parametrize('kind, key', [('things', '../escape'), ('../up', 'k'), ('things', ''),
                                       ('things', '.hidden')])
def test_names_that_could_leave_the_folder_are_refused(cache, kind, key):
    with pytest.raises(ValueError, match='cache names are letters'):
        entry_path(kind, key)


def test_an_entry_that_is_not_json_is_missing_and_says_so(cache, caplog):
    write_entry('things', 'k1', [1])
    (cache / 'things' / 'k1.json').write_text('{"half": [1, 2')
    assert read_entry('things', 'k1') is None
    assert 'ignoring the cache entry' in caplog.text


def test_a_folder_that_cannot_be_written_costs_the_entry_not_the_caller(tmp_path, monkeypatch,
                                                                        caplog):
    (tmp_path / 'a_file').write_text('not a folder')
    monkeypatch.setenv('FTPLAN_CACHE_DIR', str(tmp_path / 'a_file'))
    assert write_entry('things', 'k1', [1]) is None
    assert 'could not write the cache entry' in caplog.text and 'FTPLAN_CACHE_DIR' in caplog.text


# A writer loads cache.py on its own (it imports only the standard library): importing
# ftplan_ros.core would take longer than the race.
WRITER = '''
import importlib.util, sys
spec = importlib.util.spec_from_file_location('cache', sys.argv[1])
cache = importlib.util.module_from_spec(spec)
spec.loader.exec_module(cache)
writer = int(sys.argv[2])
for _ in range(30):
    cache.write_entry('race', 'one', {'writer': writer, 'values': [writer] * 100_000})
'''


def test_racing_writers_leave_whole_entries_only(cache):
    """Three processes write one entry again and again while it is read: every read of the
    file is one writer's whole entry, and no temporary file is left behind."""
    module = Path(cache_module.__file__)
    writers = [subprocess.Popen([sys.executable, '-c', WRITER, str(module), str(k)])
               for k in range(3)]
    path = cache / 'race' / 'one.json'
    reads = 0
    while any(w.poll() is None for w in writers):
        try:
            text = path.read_text()
        except FileNotFoundError:
            continue
        data = json.loads(text)
        assert data['values'] == [data['writer']] * 100_000
        reads += 1
    assert [w.returncode for w in writers] == [0, 0, 0]
    assert json.loads(path.read_text())['writer'] in (0, 1, 2)
    assert [p.name for p in path.parent.iterdir()] == ['one.json']
    assert reads > 0
