"""How a plan request ends: the reason of each refusal, and the status of a plan found.

The planner node (planner.py) reads a request (plan_request.py), plans it in its own
process or a worker's (plan_jobs.py, plan_pool.py) and checks that the robot is still
the one it planned for. Whatever stops it on the way is answered with an empty Path and
reported with the reason `refusal` gives; a plan found is reported with the values
`found_values` adds to its plan status (plan_info.py).
"""

from __future__ import annotations

from ftplan_ros.core import InputError, PlanResult, Scene
from ftplan_ros.core.planning.approach import Approach

from .plan_info import join_names
from .plan_jobs import PlanTimeout
from .plan_pool import PlanWorkerError
from .plan_request import RequestError, StaleInputError


def refusal(error: Exception, timeout: float) -> tuple[str, str]:
    """Return the reason and level ('WARN', or 'ERROR' for a fault of ours) of a refusal.

    `error` is what stopped the request; `timeout` [s] the planner's plan_timeout.
    """
    if isinstance(error, (InputError, RequestError)):
        return f'bad plan request: {error}', 'WARN'
    if isinstance(error, StaleInputError):
        return str(error), 'WARN'
    if isinstance(error, PlanTimeout):
        return (f'no answer within plan_timeout = {timeout:g} s: the search was stopped; '
                'raise plan_timeout or simplify the request'), 'WARN'
    if isinstance(error, PlanWorkerError):
        return f'internal planner error: {error}', 'ERROR'
    return f'internal planner error: {error!r}', 'ERROR'


def found_values(scene: Scene, result: PlanResult, approach: Approach | None,
                 ) -> dict[str, object]:
    """Return what a plan found adds to its status: the joints it tolerates, its approach."""
    tolerated = result.stats.get('tolerated_joints', []) or [
        scene.robot.joint_names[i] for i in result.tolerated_joints]
    return {'tolerated_joints': join_names(tolerated),
            'approach': 'not planned (no joint state, or the approach parameter is off)'
            if approach is None else approach.describe()}
