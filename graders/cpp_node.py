"""Grader for ``cpp-node`` (seed ch. 25-26; contract in shared/LESSONS.md).

The C++ twin of ``print-forever-node``: package ``cpp_package_with_a_node``,
executable ``print_forever_node``, node ``print_forever_node`` (or ``print_forever_cpp``, as the
tutorial's own listing names it), logging
``Printed N times.`` every 0.5 s. Graded by the same black-box checks
(graders/print_forever_node.py); only the ``package.xml`` dependency differs
(``rclcpp``). Needs rclcpp: on the PyPI install, the source-built underlay
(course/ros/underlay.py).
"""

from __future__ import annotations

from ros2course.kit import Session
from . import print_forever_node
from .print_forever_node import grade_node, make_checks

PACKAGE = "cpp_package_with_a_node"
NODE = "print_forever_node"
#: The tutorial's C++ listing (ch. 26) and its author's Jazzy code name the node so, while its printed log
#: says print_forever_node: code typed as the tutorial gives it keeps the points (issue 19).
ALIASES = ("print_forever_cpp",)
#: Seconds of observation the contract needs (benchmarks/check_speed.py reads it): the Python twin's.
WINDOW = print_forever_node.WINDOW

CHECKS = make_checks("rclcpp", PACKAGE, NODE)


def grade(s: Session) -> None:
    """Run the C++ print_forever_node, read its /rosout records, then Ctrl+C it."""
    grade_node(s, PACKAGE, NODE, "rclcpp", ALIASES)
