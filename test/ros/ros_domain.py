"""A ROS_DOMAIN_ID no other ftplan test run or benchmark on this host is using.

Each process claims the first free domain in 1..101 by holding an exclusive flock on
<tempdir>/ftplan-ros-domain-<id>.lock until it exits (the kernel releases the lock then,
however the process ends). Domain 0 is everyone's default; above 101 the DDS ports of a
domain reach Linux's ephemeral port range. Imported by the ROS tests and by
benchmarks/ros_bench.py, so it needs neither pytest nor rclpy.
"""

from __future__ import annotations

import fcntl
import os
import tempfile
from pathlib import Path
from typing import IO

DOMAINS = range(1, 102)
_held: list[IO] = []  # the open lock files: this process keeps its domains while it runs


def lock_path(domain: int) -> Path:
    """Return the lock file of `domain`."""
    return Path(tempfile.gettempdir()) / f'ftplan-ros-domain-{domain}.lock'


def claim_domain(environment: bool = True) -> int:
    """Lock the first free domain in 1..101 for the rest of this process and return it.

    With `environment` it also goes into os.environ['ROS_DOMAIN_ID'], where rclpy.init
    and every child process started afterwards read it (a second domain, for nodes that
    must not see the others, leaves it alone).
    """
    for domain in DOMAINS:
        try:
            handle = open(lock_path(domain), 'a')  # closed by the exit of this process
        except OSError:  # e.g. another user's lock file
            continue
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            continue
        _held.append(handle)
        if environment:
            os.environ['ROS_DOMAIN_ID'] = str(domain)
        return domain
    raise RuntimeError(f'every ROS domain in 1..101 is taken ({lock_path(1).parent})')
