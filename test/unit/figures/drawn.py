"""What a figure drew: artists found by their gid, the points of lines."""

import numpy as np


def artists(ax, gid):
    """The artists of `ax` whose gid is `gid`."""
    return [artist for artist in ax.get_children() if artist.get_gid() == gid]


def only(ax, gid):
    """The one artist of `ax` whose gid is `gid`."""
    found = artists(ax, gid)
    assert len(found) == 1, f'{len(found)} artists with gid {gid!r}'
    return found[0]


def arm_points(line):
    """The points (k, 2) of a 2-D line."""
    return np.column_stack(line.get_data())


def points_3d(line):
    """The points (k, 3) of a 3-D line."""
    return np.column_stack(line.get_data_3d())
