"""The kinematic chain's arrays (core/model/chain.py)."""

import numpy as np
import pytest

from ftplan_ros.core.model.chain import ChainModel


def test_a_chain_model_checks_its_arrays():
    with pytest.raises(ValueError, match='placements must have shape'):
        ChainModel('x', ('a',), ('base', 'l1'), np.zeros((2, 4, 4)), np.zeros((1, 3)),
                   np.eye(4), (None,))
    with pytest.raises(ValueError, match='n \\+ 1 links'):
        ChainModel('x', ('a',), ('base',), np.zeros((1, 4, 4)), np.zeros((1, 3)),
                   np.eye(4), (None,))
