"""Checks of plain data (core/validation.py): each names its field; numbers are bounded."""

import pytest
from ftplan_testing import paper_scene


def test_numbers_beyond_the_rounding_allowance_are_refused():
    with pytest.raises(ValueError, match=r'obstacles\[0\].radius'):
        paper_scene(obstacles=[((5.0, 0.0), 1e10)])
