"""Grader for ``cpp-node`` (seed ch. 25-26; contract in shared/LESSONS.md).

The C++ twin of ``print-forever-node``: package ``cpp_package_with_a_node``,
executable ``print_forever_node``, node ``print_forever_node`` (or ``print_forever_cpp``, as the
tutorial's own listing names it), logging
``Printed N times.`` every 0.5 s. Graded by the same black-box checks
(graders/print_forever_node.py); only ``package.xml`` differs: the ``rclcpp``
dependency, and the ``ament_cmake`` build tool this lesson's package declares (read here, as
colcon reads it). Needs rclcpp: on the PyPI install, the source-built underlay
(course/ros/underlay.py).
"""

from __future__ import annotations

from ros2course import kit
from ros2course.kit import Check, Session, checks, params
from . import print_forever_node
from .print_forever_node import grade_node, make_checks

PACKAGE = "cpp_package_with_a_node"
NODE = "print_forever_node"
#: The tutorial's C++ listing (ch. 26) and its author's Jazzy code name the node so, while its printed log
#: says print_forever_node: code typed as the tutorial gives it keeps the points (issue 19).
ALIASES = ("print_forever_cpp",)
#: Seconds of observation the contract needs (benchmarks/check_speed.py reads it): the Python twin's.
WINDOW = print_forever_node.WINDOW

CHECKS = [
    *make_checks("rclcpp", PACKAGE, NODE),
    Check("buildtool_depend", "package.xml declares the ament_cmake build tool", 1,
          "keep <buildtool_depend>ament_cmake</buildtool_depend> in package.xml, as ros2 pkg create --build-type "
          "ament_cmake writes it (seed ch. 25): colcon orders builds by it and rosdep installs it"),
    # a wall timer and rclcpp::spin (seed ch. 26), as the Python twin: a sleep loop logs the same records but
    # never serves the node's parameter services (helper audit of issue 37: it passed every check)
    checks.spins(),
]


def _buildtool_depend(s: Session) -> None:
    """Record ``buildtool_depend`` from package.xml, read with catkin_pkg as colcon reads it (never built or run).

    The build alone cannot judge it: colcon picks the build from ``<build_type>``, so a package without
    ``<buildtool_depend>ament_cmake</buildtool_depend>`` builds wherever ament_cmake is already installed;
    but ``rosdep install --from-paths src`` does not install ament_cmake for it, and in a workspace that
    builds ament_cmake too colcon need not build it first.
    """
    expected = "<buildtool_depend>ament_cmake</buildtool_depend> in package.xml"
    found = kit.source_package(s, PACKAGE)
    if found is None:
        s.record("buildtool_depend", False, f"no package {PACKAGE} in src/", expected)
        return
    tools = sorted(d.name for d in found[1].buildtool_depends)
    s.record("buildtool_depend", "ament_cmake" in tools, f"build tools: {', '.join(tools) or 'none'}", expected)


def grade(s: Session) -> None:
    """Read package.xml's build tool, run the C++ print_forever_node, read its /rosout records, then Ctrl+C it."""
    _buildtool_depend(s)
    grade_node(s, PACKAGE, NODE, "rclcpp", ALIASES, while_waiting=lambda started: params.record_spins(s, "spins", started))
