"""Checks of plain data (core/validation.py): each names its field; numbers are bounded."""

import math
import re

import pytest
from ftplan_testing import paper_scene

from ftplan_ros.core.errors import InputError
from ftplan_ros.core.validation import (
    LARGEST_NUMBER,
    check_keys,
    integer,
    mapping,
    nonnegative,
    number,
    sequence,
    vector,
)


def test_numbers_beyond_the_rounding_allowance_are_refused():
    with pytest.raises(ValueError, match=r'obstacles\[0\].radius'):
        paper_scene(obstacles=[((5.0, 0.0), 1e10)])


@pytest.mark.parametrize('value, problem', [
    (True, 'must be a number, got True'), ('1.0', "must be a number, got '1.0'"),
    (None, 'must be a number'), (math.nan, 'must be finite'), (-math.inf, 'must be finite'),
    (10 ** 400, 'must be finite'), (1.5e6, 'must be within ±1e+06, got 1.5e+06')],
    ids=['bool', 'string', 'None', 'nan', '-inf', 'int-too-big-for-a-float', 'beyond-the-bound'])
def test_a_number_is_a_finite_float_within_the_bound(value, problem):
    with pytest.raises(InputError) as caught:
        number(value, 'task.goal[0]')
    assert caught.value.field == 'task.goal[0]' and problem in caught.value.problem
    assert number(3, 'x') == 3.0 and isinstance(number(3, 'x'), float)
    assert number(-LARGEST_NUMBER, 'x') == -LARGEST_NUMBER


def test_containers_and_keys_are_checked_by_name():
    assert mapping({'a': 1}, 'robot') == {'a': 1}
    with pytest.raises(InputError, match='^robot: must be a mapping, got list'):
        mapping([1], 'robot')
    assert sequence((1, 2), 'rows') == [1, 2]
    for text in ('12', b'12'):  # strings are sequences, but not lists of values
        with pytest.raises(InputError, match='^rows: must be a list, got'):
            sequence(text, 'rows')
    check_keys({'a': 1, 'b': 2}, 'robot', required=('a',), optional=('b', 'c'))
    with pytest.raises(InputError, match=r'^robot\.d: unknown key \(allowed: a, b, c\)'):
        check_keys({'a': 1, 'd': 2}, 'robot', required=('a',), optional=('b', 'c'))
    with pytest.raises(InputError, match=r'^robot\.a: is missing'):
        check_keys({'b': 1}, 'robot', required=('a',), optional=('b',))


def test_integers_nonnegative_numbers_and_vectors():
    assert integer(4, 'chunk', least=1) == 4
    for value, problem in ((True, 'must be an integer, got True'), (2.0, 'must be an integer'),
                           (0, 'must be an integer >= 1, got 0')):
        with pytest.raises(InputError, match=f'^chunk: {re.escape(problem)}'):
            integer(value, 'chunk', least=1)
    assert nonnegative(0, 'radius') == 0.0
    with pytest.raises(InputError, match='^radius: must be >= 0, got -0.1'):
        nonnegative(-0.1, 'radius')
    assert vector((1, 2.5), 'center', length=2) == [1.0, 2.5]
    with pytest.raises(InputError, match=r'^center: needs 3 values, got 2'):
        vector([1, 2], 'center', length=3)
    with pytest.raises(InputError, match=r'^center\[1\]: must be finite'):
        vector([1, math.inf], 'center')
