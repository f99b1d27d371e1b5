"""The Dask cluster the study tests share."""

import pytest

from ftplan_ros.study import open_client


@pytest.fixture(scope='session')
def client():
    """A LocalCluster of 2 worker processes, as `ftplan study` starts one."""
    with open_client(None, workers=2) as client:    # the command's LocalCluster
        yield client
