import math

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue

from ftplan_msgs_py.diagnostics import (
    DiagnosticReading,
    create_diagnostic_array,
    create_diagnostic_status,
    read_diagnostic_status,
)


@pytest.mark.parametrize('level, raw', [('OK', DiagnosticStatus.OK),
                                        ('WARN', DiagnosticStatus.WARN),
                                        ('ERROR', DiagnosticStatus.ERROR),
                                        ('STALE', DiagnosticStatus.STALE)])
def test_levels_round_trip(level, raw):
    msg = create_diagnostic_status('planner', level, 'msg')
    assert msg.level == raw
    assert read_diagnostic_status(msg).level == level


def test_values_are_stringified_with_full_float_precision():
    values = {'third': 1 / 3, 'np_float': np.float64(2.5), 'count': 3, 'np_int': np.int64(7),
              'flag': True, 'joints': np.array([0.1, 0.2]), 'bad_input': math.nan,
              'text': 'joint2@0.5'}
    msg = create_diagnostic_status('planner', 'WARN', 'replanned', values, hardware_id='arm')
    got = {kv.key: kv.value for kv in msg.values}
    assert got == {'third': '0.3333333333333333', 'np_float': '2.5', 'count': '3',
                   'np_int': '7', 'flag': 'True', 'joints': '[0.1, 0.2]', 'bad_input': 'nan',
                   'text': 'joint2@0.5'}
    assert float(got['third']) == 1 / 3
    assert [kv.key for kv in msg.values] == list(values)


def test_round_trip():
    msg = create_diagnostic_status('ftplan executor', 'ERROR', 'collision', {'joint': 'j2'},
                                   hardware_id='arm0')
    assert read_diagnostic_status(msg) == DiagnosticReading(
        'ftplan executor', 'ERROR', 'collision', {'joint': 'j2'}, 'arm0')


def test_read_hand_built_status():
    msg = DiagnosticStatus(level=DiagnosticStatus.STALE, name='sim', message='no data',
                           values=[KeyValue(key='age_s', value='3.5')])
    reading = read_diagnostic_status(msg)
    assert (reading.name, reading.level, reading.message) == ('sim', 'STALE', 'no data')
    assert reading.values == {'age_s': '3.5'}
    assert reading.hardware_id == ''


@pytest.mark.parametrize('level', ['INFO', 'ok', 0])
def test_create_rejects_unknown_level(level):
    with pytest.raises(ValueError, match='diagnostic level .* is unknown'):
        create_diagnostic_status('planner', level, 'msg')


def test_create_rejects_bad_text_fields():
    with pytest.raises(ValueError, match='diagnostic name must be a non-empty string'):
        create_diagnostic_status('', 'OK', 'msg')
    with pytest.raises(ValueError, match='diagnostic message must be a string'):
        create_diagnostic_status('planner', 'OK', None)
    with pytest.raises(ValueError, match='diagnostic hardware_id must be a string'):
        create_diagnostic_status('planner', 'OK', 'msg', hardware_id=3)
    with pytest.raises(ValueError, match='diagnostic value key must be a non-empty string'):
        create_diagnostic_status('planner', 'OK', 'msg', {1: 'x'})
    with pytest.raises(ValueError, match='diagnostic value key must be a non-empty string'):
        create_diagnostic_status('planner', 'OK', 'msg', {'': 'x'})


def test_create_array():
    statuses = [create_diagnostic_status('a', 'OK', ''), create_diagnostic_status('b', 'WARN', '')]
    msg = create_diagnostic_array(statuses, stamp=Time(sec=9))
    assert msg.header.stamp.sec == 9
    assert [s.name for s in msg.status] == ['a', 'b']
    assert create_diagnostic_array([]).header.stamp.sec == 0


def test_create_array_rejects_other_objects():
    with pytest.raises(ValueError, match=r'statuses\[1\] is a dict'):
        create_diagnostic_array([create_diagnostic_status('a', 'OK', ''), {'name': 'b'}])


def test_read_rejects_unknown_level():
    with pytest.raises(ValueError, match="'sim' has unknown level 7"):
        read_diagnostic_status(DiagnosticStatus(level=b'\x07', name='sim'))


def test_read_rejects_duplicate_keys():
    msg = DiagnosticStatus(name='sim', values=[KeyValue(key='k', value='1'),
                                               KeyValue(key='k', value='2')])
    with pytest.raises(ValueError, match="lists key 'k' twice"):
        read_diagnostic_status(msg)
