"""The results folder (study/results.py): chunks written whole, found again, of one study only."""

import json

import pyarrow.parquet as pq
import pytest

from ftplan_ros.core import InputError
from ftplan_ros.study import ResultStore
from ftplan_ros.study.results import rows_to_table
from ftplan_ros.study.tasks import task_inputs

from .specs import MAP, spec_with, study_of


def rows_of(study, chunk, **columns):
    return rows_to_table([task_inputs(study, study.task(k)) | columns
                          for k in study.chunk_tasks(chunk)], study.dim)


def test_chunks_are_written_whole_and_found_again(tmp_path):
    study = study_of(MAP)
    store = ResultStore(tmp_path / 'out', study)
    store.open()
    assert store.finished_chunks() == set()
    store.write(2, rows_of(study, 2, feasible=True, outcome='failure_tolerant'))
    store.write(5, rows_of(study, 5, feasible=False, outcome='unreachable'))
    assert store.finished_chunks() == {2, 5}
    assert sorted(p.name for p in (tmp_path / 'out').iterdir()) == [
        'chunk-000002.parquet', 'chunk-000005.parquet', 'study.json']
    table = store.read()
    assert table.column('task').to_pylist() == [8, 9, 10, 11, 20]
    assert table.column('outcome').to_pylist() == ['failure_tolerant'] * 4 + ['unreachable']
    assert pq.read_table(store.chunk_path(5)).column('start_x').to_pylist() == [3.0]
    manifest = json.loads((tmp_path / 'out' / 'study.json').read_text())
    assert manifest['digest'] == study.digest() and manifest['tasks'] == 21
    # Reopening (a rerun) keeps the chunks and removes what a killed writer left.
    (tmp_path / 'out' / '.chunk-000003.parquet.tmp-12345').write_bytes(b'PAR1 half')
    again = ResultStore(tmp_path / 'out', study_of(MAP))
    again.open()
    assert again.finished_chunks() == {2, 5}
    assert not list((tmp_path / 'out').glob('.*'))


def test_a_chunk_with_the_wrong_tasks_is_refused(tmp_path):
    study = study_of(MAP)
    store = ResultStore(tmp_path, study)
    store.open()
    with pytest.raises(ValueError, match='chunk 1 must hold tasks 4..7'):
        store.write(1, rows_of(study, 0))
    assert store.finished_chunks() == set()


def test_a_folder_of_another_study_is_refused(tmp_path):
    ResultStore(tmp_path, study_of(MAP)).open()
    other = study_of(spec_with(MAP, ('planner',), {'margin': 0.01}))
    with pytest.raises(InputError) as caught:
        ResultStore(tmp_path, other).open()
    assert caught.value.field == '--out' and 'another study' in caught.value.problem
    stray = tmp_path / 'stray'
    stray.mkdir()
    (stray / 'chunk-000000.parquet').write_bytes(b'')
    with pytest.raises(InputError, match='no study.json'):
        ResultStore(stray, other).open()
