"""The ROS_DOMAIN_ID claim that keeps concurrent test runs and benchmarks apart."""

import os
import subprocess
import sys
from pathlib import Path

import ros_domain


def test_a_claimed_domain_is_nobody_elses_while_its_process_runs():
    mine = int(os.environ['ROS_DOMAIN_ID'])          # claimed by ros_support for this worker
    code = 'import ros_domain as d; print(d.claim_domain(), d.claim_domain())'
    child = subprocess.run([sys.executable, '-c', code], cwd=Path(ros_domain.__file__).parent,
                           capture_output=True, text=True, timeout=60)
    assert child.returncode == 0, child.stderr
    first, second = map(int, child.stdout.split())
    assert len({mine, first, second}) == 3
    # Not 0 (everyone's default); above 101 a domain's ports reach the ephemeral range.
    assert all(1 <= d <= 101 for d in (mine, first, second))
