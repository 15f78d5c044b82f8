"""The kit's static readings of a learner's files (no ROS graph): package.xml dependency kinds, CMake paths, the
words of a log record."""

from __future__ import annotations

import types

from catkin_pkg.package import parse_package_string

from ros2course.kit.cmake import hardcoded_paths
from ros2course.kit.console import console_records, log_texts
from ros2course.kit.packages import declared_dependencies
from ros2course.kit.records import names_status

_PACKAGE_XML = """<?xml version="1.0"?>
<package format="3">
  <name>p</name><version>0.0.0</version><description>d</description>
  <maintainer email="learner@example.com">a</maintainer><license>MIT</license>
  <depend>std_msgs</depend>
  <build_depend>rclpy</build_depend>
  <exec_depend>geometry_msgs</exec_depend>
</package>
"""


def test_dependency_kinds_are_told_apart_and_depend_is_every_kind() -> None:
    """REP 149: <depend> is build, build_export and exec at once; a <build_depend> alone is not one ros2 run
    sees (audit of stop 71: print-forever-node's rclpy passed so)."""
    package = parse_package_string(_PACKAGE_XML)
    assert declared_dependencies(package) == {"std_msgs", "rclpy", "geometry_msgs"}
    assert declared_dependencies(package, ("exec",)) == {"std_msgs", "geometry_msgs"}
    assert declared_dependencies(package, ("build",)) == {"std_msgs", "rclpy"}


def test_a_destination_made_absolute_from_the_prefix_is_a_hardcoded_path() -> None:
    """``DESTINATION ${CMAKE_INSTALL_PREFIX}/lib`` and ``${CMAKE_INSTALL_FULL_<dir>}`` are fixed at configure
    time; GNUInstallDirs' relative ``${CMAKE_INSTALL_LIBDIR}`` is what the lesson asks for."""
    found = hardcoded_paths("install(TARGETS g LIBRARY DESTINATION ${CMAKE_INSTALL_PREFIX}/lib)\n"
                            'install(FILES c DESTINATION "${CMAKE_INSTALL_FULL_LIBDIR}/cmake/G")\n'
                            "install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})\n"
                            "# install(FILES x DESTINATION ${CMAKE_INSTALL_PREFIX}/share)\n")
    assert found == ["DESTINATION ${CMAKE_INSTALL_PREFIX}/lib", "DESTINATION ${CMAKE_INSTALL_FULL_LIBDIR}/cmake/G"]


def test_a_record_names_a_goal_status_only_as_a_word() -> None:
    """Any case or spelling of the status, or its enum name, names it; its letters inside another word do not
    ('unsuccessful' held 'succe', so a client logging it for a goal that succeeded passed logs_result)."""
    succeeded, canceled, aborted = 4, 5, 6
    for text in ("Goal SUCCEEDED: final position (1.000, 2.000)", "goal succeeded", "Success!",
                 "status=STATUS_SUCCEEDED", "[SUCCEEDED]"):
        assert names_status(text, succeeded), text
    for text in ("Goal unsuccessful", "XXSUCCEEDEDXX", "Goal status 4", "Goal ABORTED"):
        assert not names_status(text, succeeded), text
    assert names_status("Goal cancelled by the server", canceled) and names_status("ABORTED", aborted)
    assert not names_status("uncanceled", canceled)


_CONSOLE = """[INFO] [1796113233.1] [client]: Waiting for the server...
[INFO] [1796113233.2] [other]: not the client's
[INFO] [1796113233.3] [client]: Distance to goal: 0.000 m
plain print() output
[WARN] [1796113233.4] [client]: two
lines
[INFO] [1796113233.5] [client]: Goal SUCCEEDED: final position (0.447, -0.330)
"""


class _Rosout:
    """A stand-in for the session's RosoutProbe: ``records(node=...)`` of messages with ``.msg``."""

    def __init__(self, texts: list[str]) -> None:
        self.texts = texts

    def records(self, node: str | None = None) -> list:
        return [types.SimpleNamespace(msg=text, name="client") for text in self.texts]


def test_a_record_lost_on_rosout_with_an_exiting_process_is_read_from_its_console() -> None:
    """kit.console: the console (stderr) completes /rosout after its last record, never before it, never twice
    (dev validate of actions-client: the reference's last record, logged just before it exited, never came)."""
    assert console_records(_CONSOLE, "client") == [
        "Waiting for the server...", "Distance to goal: 0.000 m plain print() output", "two lines",
        "Goal SUCCEEDED: final position (0.447, -0.330)"]
    proc = types.SimpleNamespace(stderr=lambda: _CONSOLE)
    lost = _Rosout(["Waiting for the server...", "Distance to goal: 0.000 m plain print() output"])
    assert log_texts(lost, "client", proc)[-2:] == ["two lines", "Goal SUCCEEDED: final position (0.447, -0.330)"]
    assert log_texts(lost, "client") == lost.texts, "no process: /rosout alone"
    whole = _Rosout(["Waiting for the server...", "x", "two lines", "Goal SUCCEEDED: final position (0.447, -0.330)"])
    assert log_texts(whole, "client", proc) == whole.texts, "nothing after /rosout's last: nothing added"
    unknown = _Rosout(["a record the console does not hold"])
    assert log_texts(unknown, "client", proc) == unknown.texts, "the console cut elsewhere: nothing added"
    assert log_texts(_Rosout([]), "client", proc)[0] == "Waiting for the server..."
    assert console_records("[INFO] [1.0] [client]: a\n[not a record\n", "client") == ["a"]
