"""A short fuzz of the running nodes (issue 10); benchmarks/fuzz_nodes.py runs the long one."""

from fuzzing import FuzzRun
from ros_domain import claim_domain
from ros_support import require_install

PER_INPUT = 46  # 11 inputs and services: ~500 malformed messages and requests


def test_malformed_messages_and_requests_leave_every_node_up_with_its_last_good_plan(tmp_path):
    require_install()
    report = FuzzRun(tmp_path, claim_domain(environment=False), seed=10).run(PER_INPUT)
    assert report.messages >= 500
    assert not report.problems(), report.summary() + f'\nlogs: {tmp_path}'
