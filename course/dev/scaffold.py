"""``ros2course dev new-lesson``: a new lesson that ``dev validate`` passes at once (issue 18).

Writes, in a course folder (made with its ``course.yaml`` when it does not exist):
the lesson's ``chapters/<id>/lesson.yaml`` with every field commented, a starter
(an ``ament_python`` package whose node is not registered yet), a grader on the
engine's public kit (:mod:`ros2course.kit`) with two checks besides the build, the
reference solution under ``solutions/src`` and one wrong-solution fixture. The
files are templates to edit: the node, its checks and the instructions are the
author's to replace. Nothing existing is ever overwritten.
"""

from __future__ import annotations

import re
from pathlib import Path

import yaml

from ros2course.errors import CourseError
from ros2course.lesson import ID_PATTERN, MANIFEST

_ID = re.compile(ID_PATTERN)

_COURSE_YAML = """\
# A ros2course course (ros2course.lesson.courses.CourseManifest documents each field).
id: {course_id}
title: "{title}"
version: "0.1.0"
ros_distro: jazzy
# the major version of ros2course's grading API (ros2course.kit) the graders use
kit: "2"
# wrong solutions `ros2course dev validate` grades: <fixtures>/<lesson-id>/<case>.yaml
fixtures: fixtures
# lesson ids in course order (ros2course dev new-lesson appends here)
lessons: []
"""

_LESSON_YAML = """\
# stable id: workspaces record progress under it (kebab-case)
id: {id}
# one line, shown by `ros2course list`
title: {title}
# chapter numbers of the text this lesson follows (any numbering your course uses)
chapters: [1]
# what must be installed (ros2course doctor names what is missing): rclpy, colcon, ros2cli, ...
requires: [rclpy, colcon]
# ROS packages `ros2course check` builds with colcon (--packages-up-to)
packages: [{package}]
# module graders/<grader>.py: CHECKS and grade(session)
grader: {grader}
# folder copied into the learner's workspace by `ros2course next` (relative to this folder)
starter: starter
# markdown shown by `ros2course next`: what to build, in the learner's words
instructions: |
  ## Goal

  Write the node `{node}` in the `ament_python` package `{package}`: when it
  starts it logs one line and then spins until Ctrl+C.

  The starter has the node's code; register it in `setup.py` so that
  `ros2 run {package} {executable}` finds it, then build with
  `colcon build --packages-select {package}`.

  Check your work with `ros2course check`.
# one at a time by `ros2course hint`, from gentle to nearly the answer (at least 3)
hints:
  - "ros2 run finds executables that setup.py lists under entry_points['console_scripts']."
  - "The entry is a string: '{executable} = {package}.{executable}:main'."
  - "After editing setup.py, build again: colcon build --packages-select {package}."
# the interface packages the grader imports message types from (none here)
interfaces: []
"""

_GRADER = '''\
"""Grader for ``{id}``: the node ``{node}`` of package ``{package}`` starts and stops cleanly.

A grader is a declaration of checks plus ``grade(s)`` calling the steps of the
engine's public kit (``ros2course.kit``). A step that cannot hand back its value
raises ``Unmet``; the engine then marks every check that needs it "not checked".
"""

from __future__ import annotations

from ros2course import kit
from ros2course.kit import Check, Session

PACKAGE = "{package}"
EXECUTABLE = "{executable}"
NODE = "{node}"

CHECKS = [
    # recorded by the engine when colcon builds the lesson's packages
    Check("build", "The package builds with colcon", 1),
    Check("executable", f"ros2 run finds {{EXECUTABLE}}", 2,
          f"add '{{EXECUTABLE}} = {{PACKAGE}}.{{EXECUTABLE}}:main' to console_scripts in setup.py, then colcon build"),
    Check("node_name", f"A node named {{NODE}} starts", 2, needs=("executable",),
          hint=f"pass '{{NODE}}' to super().__init__() in your Node subclass"),
]


def grade(s: Session) -> None:
    """Find the executable, start it, wait for the node in the graph."""
    path = kit.executable(s, "executable", PACKAGE, EXECUTABLE)
    kit.start_node(s, "node_name", path, NODE)
'''

_NODE = '''\
"""The node of lesson {id}: logs one line, then spins until Ctrl+C."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node


class {cls}(Node):
    def __init__(self):
        super().__init__("{node}")
        self.get_logger().info("{node} is up")


def main(args=None):
    try:
        rclpy.init(args=args)
        rclpy.spin({cls}())
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
'''

_PACKAGE_XML = """\
<?xml version="1.0"?>
<package format="3">
  <name>{package}</name>
  <version>0.0.0</version>
  <description>Lesson {id}</description>
  <maintainer email="author@example.com">author</maintainer>
  <license>Apache-2.0</license>
  <depend>rclpy</depend>
  <export>
    <build_type>ament_python</build_type>
  </export>
</package>
"""

_SETUP_PY = """\
from setuptools import find_packages, setup

package_name = "{package}"

setup(
    name=package_name,
    version="0.0.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    entry_points={{
        "console_scripts": [{entry}],
    }},
)
"""

_SETUP_CFG = """\
[develop]
script_dir=$base/lib/{package}
[install]
install_scripts=$base/lib/{package}
"""

_FIXTURE = """\
description: The node is never registered in setup.py, so ros2 run cannot find it
fails: [executable]
edits:
  - file: src/{package}/setup.py
    replace: "\\"{executable} = {package}.{executable}:main\\""
    with: ""
"""


def _package_files(root: Path, names: dict[str, str], registered: bool) -> dict[Path, str]:
    package = names["package"]
    entry = f'"{names["executable"]} = {package}.{names["executable"]}:main"' if registered else ""
    return {
        root / package / "package.xml": _PACKAGE_XML.format(**names),
        root / package / "setup.py": _SETUP_PY.format(**names, entry=entry),
        root / package / "setup.cfg": _SETUP_CFG.format(**names),
        root / package / "resource" / package: "",
        root / package / package / "__init__.py": "",
        root / package / package / f"{names['executable']}.py": _NODE.format(**names),
    }


def new_lesson(course_root: Path, lesson_id: str, title: str | None = None) -> list[Path]:
    """Scaffold lesson ``lesson_id`` in the course at ``course_root``; return the files written.

    Makes the course (``course.yaml``, ``graders/``) when ``course_root`` holds none, and
    appends the lesson to ``course.yaml``'s ``lessons``. The lesson's ROS package is
    ``<id with underscores>_pkg`` with the executable ``<id>_node`` (underscores; ``<id>`` alone
    when it ends in ``node``) and the node of the same name.

    Raises:
        CourseError: the id is not kebab-case, or the lesson (or any file it needs) exists already.
    """
    if not _ID.match(lesson_id):
        raise CourseError(f"lesson id {lesson_id!r} is not kebab-case", "e.g. my-first-node (lowercase, digits, dashes)")
    snake = lesson_id.replace("-", "_")
    node = snake if snake.endswith("node") else f"{snake}_node"
    names = {"id": lesson_id, "title": title or lesson_id.replace("-", " ").capitalize(), "package": f"{snake}_pkg",
             "executable": node, "node": node, "grader": snake,
             "cls": "".join(part.capitalize() for part in lesson_id.split("-")) + "Node"}
    manifest_path = course_root / MANIFEST
    files: dict[Path, str] = {}
    if not manifest_path.exists():
        files[manifest_path] = _COURSE_YAML.format(course_id=course_root.resolve().name.lower().replace("_", "-"),
                                                   title=f"The course {course_root.resolve().name}")
        files[course_root / "graders" / "__init__.py"] = '"""This course\'s graders: one module per lesson."""\n'
    data = yaml.safe_load(files.get(manifest_path) or manifest_path.read_text(encoding="utf-8")) or {}
    lessons = list(data.get("lessons") or [])
    if lesson_id in lessons:
        raise CourseError(f"{manifest_path}: lessons: {lesson_id!r} exists already", "choose another id")
    chapters = course_root / "chapters"
    folder = chapters / lesson_id  # named by its id: its place in the course is course.yaml's lessons: order

    files[folder / "lesson.yaml"] = _LESSON_YAML.format(**names)
    files.update(_package_files(folder / "starter" / "src", names, registered=False))
    files.update(_package_files(course_root / "solutions" / "src", names, registered=True))
    files[course_root / "graders" / f"{snake}.py"] = _GRADER.format(**names)
    fixtures = course_root / str(data.get("fixtures") or "fixtures")
    files[fixtures / lesson_id / "never-registered.yaml"] = _FIXTURE.format(**names)
    taken = [path for path in files if path.exists() and path != manifest_path]
    if taken:
        raise CourseError(f"{taken[0]} exists already; nothing was written",
                          "choose another lesson id, or move that file away")
    for path, text in files.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    # append the id to the manifest's lessons, keeping the author's comments
    text = manifest_path.read_text(encoding="utf-8")
    if re.search(r"^lessons:[ \t]*\[[ \t]*\][ \t]*$", text, flags=re.M):
        text = re.sub(r"^lessons:[ \t]*\[[ \t]*\][ \t]*$", f"lessons:\n  - {lesson_id}", text, count=1, flags=re.M)
    elif re.search(r"^lessons:[ \t]*$", text, flags=re.M):
        text = text.rstrip("\n") + f"\n  - {lesson_id}\n"  # the block list is the file's last field
    else:
        raise CourseError(f"{manifest_path}: lessons: cannot append {lesson_id!r} automatically",
                          "write 'lessons:' as a block list at the end of course.yaml, or add the id by hand")
    manifest_path.write_text(text, encoding="utf-8")
    return sorted(files)


__all__ = ["new_lesson"]
