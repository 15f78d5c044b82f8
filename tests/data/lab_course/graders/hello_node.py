"""Grader for ``hello-node``: the node ``hello_node`` of package ``hello_node_pkg`` starts and stops cleanly.

A grader is a declaration of checks plus ``grade(s)`` calling the steps of the
engine's public kit (``ros2course.kit``). A step that cannot hand back its value
raises ``Unmet``; the engine then marks every check that needs it "not checked".
"""

from __future__ import annotations

from ros2course import kit
from ros2course.kit import Check, GradingSession

PACKAGE = "hello_node_pkg"
EXECUTABLE = "hello_node"
NODE = "hello_node"

CHECKS = [
    # recorded by the engine when colcon builds the lesson's packages
    Check("build", "The package builds with colcon", 1),
    Check("executable", f"ros2 run finds {EXECUTABLE}", 2,
          f"add '{EXECUTABLE} = {PACKAGE}.{EXECUTABLE}:main' to console_scripts in setup.py, then colcon build"),
    Check("node_name", f"A node named {NODE} starts", 2, needs=("executable",),
          hint=f"pass '{NODE}' to super().__init__() in your Node subclass"),
]


def grade(s: GradingSession) -> None:
    """Find the executable, start it, wait for the node in the graph."""
    path = kit.executable(s, "executable", PACKAGE, EXECUTABLE)
    kit.start_node(s, "node_name", path, NODE)
