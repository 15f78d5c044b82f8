"""Check declarations that several graders share, worded the same in every lesson.

Each returns :class:`~ros2course.grade.checks.Check` objects for a grader's
``CHECKS``: the learner's executable found by ``ros2 run``, its node's name,
its Ctrl+C exit (tutorial ch. 13), the interface lessons' dependencies
(seed ch. 18.1). Keyword arguments ``needs`` and ``part`` are the Check's.
"""

from __future__ import annotations

from ros2course.grade.checks import Check

#: The fix for a node that ends with a traceback on Ctrl+C (Jazzy: ``rclpy.spin()`` may raise
#: ``ExternalShutdownException``; shared/ROS_ENV.md).
SIGINT_HINT = "catch (KeyboardInterrupt, ExternalShutdownException) around rclpy.spin()"


def interfaces_depend() -> Check:
    """``depends``: package.xml depends on rclpy and package_with_interfaces (1 point)."""
    return Check("depends", "package.xml depends on rclpy and package_with_interfaces", 1,
                 "add <depend>rclpy</depend> and <depend>package_with_interfaces</depend> to package.xml "
                 "(seed ch. 18.1)")


def started(prefix: str, package: str, executable: str, node: str, *, part: str) -> list[Check]:
    """``<prefix>_executable`` (``ros2 run`` finds it) and ``<prefix>_node_name`` (a node called ``node``
    starts; needs the executable), 1 point each, in ``part``."""
    return [
        Check(f"{prefix}_executable", f"ros2 run finds {executable}", 1,
              f"register '{executable} = {package}.{executable}:main' in console_scripts, then colcon build",
              part=part),
        Check(f"{prefix}_node_name", f"A node named {node} starts", 1, f"pass '{node}' to super().__init__()",
              needs=(f"{prefix}_executable",), part=part),
    ]


def ctrl_c(check_id: str, what: str, points: float = 1, hint: str = SIGINT_HINT, *, needs: tuple[str, ...] = (),
           part: str = "") -> Check:
    """``check_id``: Ctrl+C ends ``what`` (e.g. "the publisher") with exit code 0 and no traceback."""
    return Check(check_id, f"Ctrl+C ends {what} with exit code 0 and no traceback", points, hint, needs=needs,
                 part=part)
