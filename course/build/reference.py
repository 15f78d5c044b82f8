"""The course's own reference packages (``solutions/src``): copied into workspaces and built.

``dev validate`` grades copies of them (and of wrong solutions made from them);
batch grading builds the interface packages a lesson's grader imports from
them, so the grader never imports a submission's generated code
(:func:`trusted_interface_packages`).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from course.build.colcon import build_packages, dependency_closure, find_packages
from course.errors import CourseError, ValidationFailed
from course.lesson.catalog import Lesson, content_root
from course.ros import env as env_mod


def solution_packages() -> dict[str, tuple[Path, object]]:
    """Every package under ``solutions/src``: name -> (folder, catkin_pkg Package)."""
    return find_packages(content_root() / "solutions" / "src")


def reference_workspace(lesson: Lesson, dest: Path, packages: list[str] | None = None, *,
                        with_folders: bool = True) -> Path:
    """Copy reference packages from ``solutions/src`` into ``dest/src``, and the lesson's ``folders``.

    Args:
        packages: which ones (default: the lesson's packages and their dependencies).
        with_folders: also copy the lesson's non-ROS ``folders`` from ``solutions/`` (a case's
            workspace needs them; an underlay of dependencies does not).

    Raises:
        ValidationFailed: a folder the lesson names is not in ``solutions/``.
    """
    solutions = content_root() / "solutions"
    found = solution_packages()
    (dest / "src").mkdir(parents=True, exist_ok=True)
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info")
    for name in (dependency_closure(lesson.packages, found) if packages is None else packages):
        shutil.copytree(found[name][0], dest / "src" / found[name][0].name, ignore=ignore)
    for folder in lesson.folders if with_folders else ():
        if not (solutions / folder).is_dir():
            raise ValidationFailed(f"lesson {lesson.id} names folder {folder!r}, which is not in solutions/")
        shutil.copytree(solutions / folder, dest / folder, ignore=ignore, dirs_exist_ok=True)
    return dest


def lesson_dependencies(lesson: Lesson) -> list[str]:
    """Reference packages the lesson's packages depend on but does not itself teach (e.g. interfaces)."""
    return [name for name in dependency_closure(lesson.packages, solution_packages()) if name not in lesson.packages]


def trusted_interface_packages(lessons: list[Lesson]) -> list[str]:
    """The reference packages batch grading must build for ``lessons``' graders: their declared
    ``interfaces`` (lesson.yaml) and what those depend on in ``solutions/src``, sorted.

    Derived from what each grader imports, never from the lesson's own packages: a lesson that
    teaches ``package_with_interfaces`` and grades with its types still gets the course's copy.

    Raises:
        CourseError: a lesson declares an interface package ``solutions/src`` does not have
            (the course is broken; no class can be graded on it).
    """
    found = solution_packages()
    for lesson in lessons:
        unknown = [name for name in lesson.interfaces if name not in found]
        if unknown:
            raise CourseError(f"lesson {lesson.id} cannot be graded in batch: its grader imports "
                              f"{', '.join(unknown)} types, and the course has no reference package of that name "
                              f"in {content_root() / 'solutions' / 'src'}",
                              "a fault of the course: add the package to solutions/src or fix 'interfaces:' "
                              "in lesson.yaml")
    return dependency_closure(list(dict.fromkeys(p for lesson in lessons for p in lesson.interfaces)), found)


def build_reference(lesson: Lesson, dest: Path, packages: list[str], log_name: str) -> Path:
    """Copy ``packages`` from ``solutions/src`` into ``dest`` and build them with colcon.

    Returns:
        ``dest`` (its ``install/`` is the build).

    Raises:
        CourseError: they do not build (a fault of the course or the machine), the excerpt of the build log
            in the message.
    """
    reference_workspace(lesson, dest, packages, with_folders=False)
    env = dict(os.environ)
    env_mod.activate(env)
    built = build_packages(dest, packages, env, dest / "log" / log_name)
    if not built.ok:
        raise CourseError(f"the course's own packages {', '.join(packages)} do not build:\n{built.excerpt}",
                          f"run ros2course doctor; see {built.log_path}")
    return dest
