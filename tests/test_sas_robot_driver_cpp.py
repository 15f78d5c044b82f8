"""The sas-robot-driver grader on the seed's C++ driver (ch. 31), built on the real SmartArmStack.

``tests/data/sas_cpp/sas_robot_driver_myrobot`` holds the seed's C++ package
(driver class, node, launch file, and the client script installed as the seed
does: ``joint_interface_example.py`` with ``#!/usr/bin/python3``). Built on the
real ``sas`` packages it must get full marks from the same black-box grader as
the lesson's Python package. sas is not on PyPI: on the pip install it is the
optional underlay component (``ros2course env --build --with sas``,
course/ros/underlay.py); with a system ROS, ``ros-jazzy-sas-*``. Skipped where
neither is installed.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest


def _sas_installed() -> bool:
    try:
        from ament_index_python.packages import get_package_prefix  # noqa: PLC0415

        get_package_prefix("sas_robot_driver")
        return True
    except Exception:  # noqa: BLE001 - no ament index, no package: not installed
        return False


pytestmark = [
    pytest.mark.ros,
    # they compile C++: never beside each other (conftest.cpu_exclusive), which may wait for them
    pytest.mark.usefixtures("cpu_exclusive"),
    pytest.mark.timeout(1200),
    pytest.mark.skipif(not _sas_installed(), reason="SmartArmStack (sas_robot_driver) is not installed: "
                       "build it with 'ros2course env --build --with sas' (or install ros-jazzy-sas-*)"),
]


@pytest.mark.timeout(900)
def test_grader_gives_the_seeds_cpp_driver_full_marks(tmp_path: Path):
    from ros2course.grade.engine import grade_lesson  # noqa: PLC0415
    from ros2course.lesson.catalog import load_catalog

    source = Path(__file__).parent / "data" / "sas_cpp" / "sas_robot_driver_myrobot"
    shutil.copytree(source, tmp_path / "src" / "sas_robot_driver_myrobot")
    lesson = load_catalog().get("sas-robot-driver")
    result = grade_lesson(lesson, tmp_path)
    failed = [f"{c.id}: {c.observed} (expected {c.expected})" for c in result.checks if not c.passed]
    assert result.status == "passed", result.message + "\n" + "\n".join(failed)
