"""A GetPlan request read into a scene (plan_request.py) and how a request ends (plan_service.py).

Requests built by hand, no DDS: every field that cannot be used is named.
"""

import numpy as np
import pytest
from ftplan_testing import SCENES
from geometry_msgs.msg import PoseStamped
from nav_msgs.srv import GetPlan
from std_msgs.msg import Header

from ftplan_msgs_py import create_pose
from ftplan_ros.core import InputError, load_scene
from ftplan_ros.nodes.plan_jobs import PlanTimeout
from ftplan_ros.nodes.plan_pool import PlanWorkerError
from ftplan_ros.nodes.plan_request import (
    RequestError,
    RequestSettings,
    StaleInputError,
    check_settings,
    read_request,
)
from ftplan_ros.nodes.plan_service import refusal

FIG3A = load_scene(SCENES / 'fig3a.yaml')
SETTINGS = RequestSettings()


def pose(x, y, z=0.0, frame='base_link', orientation=None) -> PoseStamped:
    return PoseStamped(header=Header(frame_id=frame), pose=create_pose([x, y, z], orientation))


def request(start=None, goal=None, tolerance=0.0) -> GetPlan.Request:
    return GetPlan.Request(start=start or PoseStamped(), goal=goal or PoseStamped(),
                           tolerance=tolerance)


def test_a_request_gives_the_scene_its_task_and_tolerances():
    scene = read_request(request(pose(2.0, 0.0), pose(1.0, 0.5), 0.02), FIG3A,
                         RequestSettings(tolerate=('joint1', 'joint3')), None, '')
    assert scene.task.start == (2.0, 0.0) and scene.task.goal == (1.0, 0.5)
    assert scene.task.goal_tolerance == pytest.approx(0.02)
    assert scene.tolerated_joints == (0, 2)
    assert scene.obstacles == FIG3A.obstacles


def test_empty_frames_mean_the_arm_where_it_is_and_the_scene_goal():
    q = np.array([0.3, 0.2, 0.1])
    scene = read_request(request(), FIG3A, SETTINGS, q, '')
    assert np.allclose(scene.task.start, FIG3A.robot.forward_kinematics(q))
    assert scene.task.goal == FIG3A.task.goal
    assert scene.task.goal_tolerance == FIG3A.task.goal_tolerance   # 0: the scene's
    with pytest.raises(InputError, match='start: empty frame_id asks for the current '
                                         'position, but no joint state yet'):
        read_request(request(), FIG3A, SETTINGS, None, 'no joint state yet')


@pytest.mark.parametrize('bad, field, problem', [
    (request(pose(2.0, 0.0, frame='map')), 'start.header.frame_id', "unknown frame 'map'"),
    (request(pose(2.0, 0.0, 0.5)), 'start.pose.position.z', 'the planar arm works in z = 0'),
    (request(pose(2.0, 0.0), tolerance=-1.0), 'tolerance', 'must be >= 0'),
    (request(pose(2.0, 0.0), tolerance=float('nan')), 'tolerance', 'must be >= 0'),
    (request(pose(2.0, 0.0), tolerance=1e-40), 'tolerance',
     'below the smallest normal float32'),
])
def test_a_field_that_cannot_be_used_is_named(bad, field, problem):
    with pytest.raises(InputError) as raised:
        read_request(bad, FIG3A, SETTINGS, None, '')
    assert raised.value.field == field and problem in str(raised.value)


def test_a_position_that_is_not_a_number_is_named():
    nan = pose(2.0, 0.0)
    nan.pose.position.y = float('nan')
    with pytest.raises(RequestError, match=r'start\.pose\.position.*\(planar task\)'):
        read_request(request(nan), FIG3A, SETTINGS, None, '')


def test_the_settings_must_fit_the_scene():
    check_settings(FIG3A, SETTINGS)
    with pytest.raises(InputError, match='task_kind'):
        check_settings(FIG3A, RequestSettings(task_kind='pose'))
    with pytest.raises(InputError, match='elbow'):
        check_settings(FIG3A, RequestSettings(tolerate=('elbow',)))


@pytest.mark.parametrize('error, reason, level', [
    (InputError('goal', 'is bad'), 'bad plan request: goal: is bad', 'WARN'),
    (RequestError('start.pose: NaN'), 'bad plan request: start.pose: NaN', 'WARN'),
    (StaleInputError('updates lost'), 'updates lost', 'WARN'),
    (PlanTimeout(), 'no answer within plan_timeout = 2.5 s: the search was stopped; raise '
                    'plan_timeout or simplify the request', 'WARN'),
    (PlanWorkerError('worker 2 died'), 'internal planner error: worker 2 died', 'ERROR'),
    (KeyError('x'), "internal planner error: KeyError('x')", 'ERROR'),
])
def test_each_way_a_request_can_fail_has_its_reason(error, reason, level):
    assert refusal(error, 2.5) == (reason, level)
