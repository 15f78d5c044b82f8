"""Copies the bundled tutorial course into the wheel (pyproject.toml holds everything else).

setuptools' package data must live inside a package folder, while the repository keeps
the course at its top level (course.yaml, chapters/, graders/, solutions/, tests/fixtures/,
gradescope/); build_py copies those folders under ``ros2course/_courses/tutorial`` of the
build, which :func:`ros2course.lesson.courses.bundled_course` finds in an installed wheel.
An editable install finds the course in the source checkout instead.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
#: what a course folder holds (course.yaml names the fixtures folder: tests/fixtures)
COURSE_PARTS = ("course.yaml", "chapters", "graders", "solutions", "tests/fixtures", "gradescope")
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info", "build", "install", "log")


class BuildWithCourse(build_py):
    """build_py, then the tutorial course's files as data of ``ros2course._courses.tutorial``."""

    def run(self) -> None:
        super().run()
        if self.editable_mode:  # the checkout is the course; nothing to copy
            return
        target = Path(self.build_lib) / "ros2course" / "_courses" / "tutorial"
        for part in COURSE_PARTS:
            source = ROOT / part
            if source.is_dir():
                shutil.copytree(source, target / part, ignore=IGNORE, dirs_exist_ok=True, symlinks=True)
            elif source.is_file():
                target.mkdir(parents=True, exist_ok=True)
                shutil.copy2(source, target / part)


setup(cmdclass={"build_py": BuildWithCourse})
