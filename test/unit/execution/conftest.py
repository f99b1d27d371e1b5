"""The executor's fixtures: it holds the Fig. 3(a) plan (rig.py plays the arm and the clock)."""

import pytest

from .rig import Rig


@pytest.fixture
def rig(fig3a):
    """An executor holding the Fig. 3(a) plan, the arm not heard from yet."""
    return Rig(*fig3a)


@pytest.fixture
def make_rig(fig3a):
    """Return make(**changes) -> Rig: another surface, tolerated joints, goal, options."""
    return lambda **changes: Rig(*fig3a, **changes)
