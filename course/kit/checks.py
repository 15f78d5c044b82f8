"""Check declarations that several graders share, worded the same in every lesson.

Each returns :class:`~ros2course.grade.checklist.Check` objects for a grader's
``CHECKS``: the learner's executable found by ``ros2 run``, its node's name,
its Ctrl+C exit (tutorial ch. 13), the interface lessons' dependencies
(seed ch. 18.1). Keyword arguments ``needs`` and ``part`` are the Check's.
"""

from __future__ import annotations

from ros2course.grade.checklist import Check

#: The fix for a node that ends with a traceback on Ctrl+C (Jazzy: ``rclpy.spin()`` may raise
#: ``ExternalShutdownException``; shared/ROS_ENV.md).
SIGINT_HINT = "catch (KeyboardInterrupt, ExternalShutdownException) around rclpy.spin()"


def interfaces_depend() -> Check:
    """``depends``: package.xml depends on rclpy and package_with_interfaces (1 point)."""
    return Check("depends", "package.xml depends on rclpy and package_with_interfaces", 1,
                 "add <depend>rclpy</depend> and <depend>package_with_interfaces</depend> to package.xml "
                 "(seed ch. 18.1)")


def console_script_hint(package: str, executable: str) -> str:
    """The fix for a Python executable ``ros2 run`` does not find (ament_python, tutorial ch. 12-13)."""
    return f"add '{executable} = {package}.{executable}:main' to console_scripts in setup.py, then colcon build"


def cmake_executable_hint(executable: str, source: str) -> str:
    """The fix for a C++ executable ``ros2 run`` does not find (ament_cmake, tutorial ch. 27)."""
    return (f"add_executable({executable} {source}) and install(TARGETS {executable} DESTINATION "
            "lib/${PROJECT_NAME}) in CMakeLists.txt, then colcon build")


def node_name_hint(node: str, client_library: str = "rclpy") -> str:
    """The fix for a node that starts under another name: the name its constructor gives."""
    if client_library == "rclcpp":
        return f'pass "{node}" to the rclcpp::Node constructor'
    return f"pass '{node}' to super().__init__()"


def started(prefix: str, package: str, executable: str, node: str, *, part: str = "", points: float = 1,
            node_points: float | None = None, client_library: str = "rclpy", executable_hint: str | None = None,
            node_hint: str | None = None, node_needs: tuple[str, ...] | None = None,
            node_part: str | None = None) -> list[Check]:
    """The executable / node-name pair every node lesson grades, worded the same in every lesson.

    ``<prefix>_executable`` (``ros2 run PACKAGE EXECUTABLE`` finds it) and ``<prefix>_node_name``
    (a node called ``node`` joins the graph; needs the executable); with ``prefix=""`` the ids
    are ``executable`` and ``node_name`` (a lesson with one node).

    Args:
        points: the executable check's points; ``node_points`` the node name's (default: the same).
        client_library: ``rclpy`` (the hints name console_scripts and ``super().__init__()``) or
            ``rclcpp`` (give ``executable_hint``, e.g. :func:`cmake_executable_hint`).
        executable_hint, node_hint: replace the standard hints (say more, never something else).
        node_needs: the node name check's needs (default: the executable check).
        node_part: the node name check's part (default: ``part``).
    """
    ids = (f"{prefix}_executable", f"{prefix}_node_name") if prefix else ("executable", "node_name")
    return [
        Check(ids[0], f"ros2 run finds {executable}", points,
              executable_hint or console_script_hint(package, executable), part=part),
        Check(ids[1], f"A node named {node} starts", points if node_points is None else node_points,
              node_hint or node_name_hint(node, client_library),
              needs=(ids[0],) if node_needs is None else node_needs, part=part if node_part is None else node_part),
    ]


def ctrl_c(check_id: str, what: str, points: float = 1, hint: str = SIGINT_HINT, *, needs: tuple[str, ...] = (),
           part: str = "") -> Check:
    """``check_id``: Ctrl+C ends ``what`` (e.g. "the publisher") with exit code 0 and no traceback."""
    return Check(check_id, f"Ctrl+C ends {what} with exit code 0 and no traceback", points, hint, needs=needs,
                 part=part)


def spins(check_id: str = "spins", needs: tuple[str, ...] = ("executable",), part: str = "") -> Check:
    """``check_id``: the node spins, so it answers its parameter services (1 point); judged by
    :func:`ros2course.kit.params.record_spins`.

    The lessons put periodic work in a timer callback and spin the node (seed ch. 13.3): a
    ``while True`` loop with ``time.sleep`` logs and publishes the same, but never lets
    the node answer anything. print-forever-node, publisher-subscriber and use-python-library grade it.
    """
    return Check(check_id, "The node spins: it answers calls to its parameter services at once (ros2 param list)",
                 1, "put the periodic work in a timer callback (self.create_timer) and call rclpy.spin(node) in "
                 "main(): a while loop with time.sleep never lets the node answer anything, or (with a spin_once "
                 "between sleeps) only now and then", needs=needs, part=part)
