"""Study specs for the tests, as plain data, and their parsing."""

import json

from ftplan_testing import SCENES

from ftplan_ros.study import parse_study

MAP = {'scene': 'fig3a.yaml', 'vary': {'start': {'x': [-3.0, 3.0, 7], 'y': [-1.0, 1.0, 3]}},
       'chunk': 4}
SWEEP = {'scene': 'paper_a_free.yaml',
         'vary': {'random': {'tasks': 40, 'seed': 3, 'start': {'radius': [1.8, 2.6]},
                             'goal': {'x': [0.5, 1.5], 'y': [-1.0, 1.0]},
                             'obstacles': {'count': [1, 4], 'radius': [0.1, 0.3]}}},
         'planner': {'seed': 0, 'margin': 0.0}, 'chunk': 7}


def spec_with(base, path, value):
    """A copy of the spec `base` with the item at `path` set to `value` (KeyError: deleted)."""
    data = json.loads(json.dumps(base))
    node = data
    for key in path[:-1]:
        node = node[key]
    if value is KeyError:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return data


def study_of(data, name='test'):
    """The study of the spec `data`, its scene named relative to config/scenes."""
    return parse_study(data, name=name, directory=SCENES)
