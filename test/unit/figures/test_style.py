"""What every figure shares (figures/style.py): the canvas, colours and texts."""

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg

from ftplan_ros.core.paper.result import PlanResult
from ftplan_ros.figures.style import (
    HIT_COLOURS,
    degrees_text,
    hit_colour,
    new_figure,
    reason_title,
)


def test_a_new_figure_has_its_own_agg_canvas_and_size():
    figure = new_figure((4.0, 3.0))
    assert isinstance(figure.canvas, FigureCanvasAgg) and figure.canvas.figure is figure
    assert tuple(figure.get_size_inches()) == (4.0, 3.0) and not figure.axes


def test_each_joint_has_its_colour_and_an_eighth_joint_takes_the_first_again():
    assert len({hit_colour(joint) for joint in range(7)}) == 7
    assert hit_colour(7) == hit_colour(0) == HIT_COLOURS[0]


def test_angles_are_written_in_degrees_and_reasons_wrapped():
    assert degrees_text(np.radians([-75.43, 101.4, 6.0])) == '[-75.4°, 101.4°, 6.0°]'
    reason = 'no candidate start passes the necessary condition of the paper ' * 2
    title = reason_title(PlanResult(False, ('a',), reason=reason), width=40)
    lines = title.splitlines()
    assert len(lines) > 2 and all(len(line) <= 40 for line in lines)
    assert ' '.join(lines) == f'No failure-tolerant plan: {reason.strip()}'
    assert reason_title(PlanResult(False, ('a',))) == 'No failure-tolerant plan: no reason given'
