"""Unit tests, laid out as ftplan_ros/ftplan_ros is: a test file per module.

The core's subpackages sit directly under test/unit (model/test_robot.py tests
core/model/robot.py), as do the core's base modules (test_validation.py); bench/, study/
and figures/ mirror their packages, and test_cli.py tests cli.py. test_layers.py and
test_style.py check the whole package. The folders are packages so that modules of the
same name in different packages (figures/spatial.py, bench/spatial.py) get test files of
the same name.
"""
