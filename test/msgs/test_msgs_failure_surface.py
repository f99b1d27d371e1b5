import math

import numpy as np
import pytest
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, MultiArrayLayout

from ftplan_msgs_py.failure_surface import create_failure_surface, read_failure_surface


def surface(K=4, W=5, n=3):
    return np.random.default_rng(2).uniform(-math.pi, math.pi, size=(K, W, n))


def hand_built(data, dims, data_offset=0):
    return Float64MultiArray(
        layout=MultiArrayLayout(
            dim=[MultiArrayDimension(label=label, size=size, stride=stride)
                 for label, size, stride in dims],
            data_offset=data_offset,
        ),
        data=list(data),
    )


def test_create_layout_follows_row_major_convention():
    paths = surface(K=4, W=5, n=3)
    msg = create_failure_surface(paths)
    assert [(d.label, d.size, d.stride) for d in msg.layout.dim] == [
        ('path', 4, 60), ('waypoint', 5, 15), ('joint', 3, 3)]
    assert msg.layout.data_offset == 0
    assert len(msg.data) == 60
    # Element (k, w, j) sits at k * dim[1].stride + w * dim[2].stride + j.
    assert msg.data[2 * 15 + 3 * 3 + 1] == paths[2, 3, 1]


def test_round_trip():
    paths = surface(K=3, W=7, n=4)
    assert np.allclose(read_failure_surface(create_failure_surface(paths)), paths)


def test_read_hand_built_honours_data_offset():
    data = [99.0, 98.0] + [float(i) for i in range(12)]
    msg = hand_built(data, [('path', 2, 12), ('waypoint', 3, 6), ('joint', 2, 2)],
                     data_offset=2)
    web = read_failure_surface(msg)
    assert web.shape == (2, 3, 2)
    assert np.allclose(web.ravel(), np.arange(12))
    assert web[1, 2, 0] == 10.0


@pytest.mark.parametrize('labels', [
    ('waypoint', 'path', 'joint'),
    ('paths', 'waypoint', 'joint'),
    ('path', 'waypoint'),
])
def test_read_rejects_wrong_labels(labels):
    dims = [(label, 1, 1) for label in labels]
    with pytest.raises(ValueError, match='layout labels are'):
        read_failure_surface(hand_built([0.0], dims))


def test_read_rejects_default_message():
    with pytest.raises(ValueError, match=r'labels are \[\]'):
        read_failure_surface(Float64MultiArray())


def test_read_rejects_wrong_strides():
    dims = [('path', 2, 6), ('waypoint', 3, 3), ('joint', 1, 0)]
    with pytest.raises(ValueError, match=r'strides are \[6, 3, 0\].*needs \[6, 3, 1\]'):
        read_failure_surface(hand_built(np.zeros(6), dims))


def test_read_rejects_short_and_long_data():
    dims = [('path', 2, 12), ('waypoint', 3, 6), ('joint', 2, 2)]
    with pytest.raises(ValueError, match='has 11 values after data_offset 0 .* needs 12'):
        read_failure_surface(hand_built(np.zeros(11), dims))
    with pytest.raises(ValueError, match='has 13 values'):
        read_failure_surface(hand_built(np.zeros(13), dims))


def test_read_rejects_data_offset_that_leaves_too_little_data():
    dims = [('path', 2, 12), ('waypoint', 3, 6), ('joint', 2, 2)]
    with pytest.raises(ValueError, match='has 10 values after data_offset 2'):
        read_failure_surface(hand_built(np.zeros(12), dims, data_offset=2))
    with pytest.raises(ValueError, match='has 0 values after data_offset 50'):
        read_failure_surface(hand_built(np.zeros(12), dims, data_offset=50))


@pytest.mark.parametrize('bad', [math.nan, -math.inf])
def test_read_rejects_non_finite_values_naming_the_element(bad):
    paths = surface(K=2, W=2, n=3)
    msg = create_failure_surface(paths)
    msg.data[1 * 6 + 0 * 3 + 2] = bad
    with pytest.raises(ValueError, match='path 1, waypoint 0, joint 2'):
        read_failure_surface(msg)


@pytest.mark.parametrize('paths', [np.zeros((4, 3)), np.zeros((2, 2, 2, 2))])
def test_create_rejects_arrays_that_are_not_three_dimensional(paths):
    with pytest.raises(ValueError, match=r'pass \(K, W, n\)'):
        create_failure_surface(paths)


def test_create_rejects_non_finite_values():
    paths = surface()
    paths[0, 1, 2] = math.nan
    with pytest.raises(ValueError, match=r'non-finite value .* \(0, 1, 2\)'):
        create_failure_surface(paths)
