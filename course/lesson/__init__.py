"""The lesson catalog: courses, lessons, starters, the learner's progress."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

#: the manifest every course folder holds (issue 18): id, title, version, ROS distro, lessons in order
MANIFEST = "course.yaml"
#: A lesson or course id: kebab-case, as rustlings and exercism name exercises (``print-forever-node``).
ID_PATTERN = r"^[a-z][a-z0-9]*(-[a-z0-9]+)*$"

_active: Path | None = None


def bundled_course() -> Path:
    """The folder of the tutorial course shipped with ros2course.

    In an installed wheel it is ``ros2course/_courses/tutorial`` (setup.py copies it
    there); in a source checkout (editable install) it is the checkout itself, which
    holds ``course.yaml`` beside ``course/``. Registered as the ``ros2-tutorial``
    entry point of the ``ros2course.courses`` group (pyproject.toml).
    """
    engine = Path(__file__).resolve().parents[1]
    installed = engine / "_courses" / "tutorial"
    return installed if (installed / MANIFEST).is_file() else engine.parent


def use_course(root: Path | None) -> None:
    """Make ``root`` the course every later :func:`content_root` call answers (None: back to the default).

    The CLI calls it once per command, from ``--course`` or the workspace's record.
    """
    global _active  # noqa: PLW0603 - one active course per process, set by the CLI before any command
    _active = root.resolve() if root is not None else None


def content_root() -> Path:
    """The active course's folder, holding ``course.yaml``, ``chapters/``, ``graders/`` and ``solutions/``.

    In order: the course chosen with :func:`use_course` (``--course``, the workspace's
    record); ``ROS2COURSE_CONTENT`` (how a batch worker subprocess is told its course,
    and tests' private copies); the bundled tutorial course (:func:`bundled_course`).
    Here rather than in :mod:`ros2course.lesson.catalog` so ``list`` finds the course without pydantic.
    """
    if _active is not None:
        return _active
    override = os.environ.get("ROS2COURSE_CONTENT")
    return Path(override).resolve() if override else bundled_course()


@dataclasses.dataclass(frozen=True)
class Course:
    """A course: the folder holding ``course.yaml``, ``chapters/``, ``graders/`` and ``solutions/``.

    The CLI resolves the course of a command once (``--course``, the workspace's record, the bundled
    tutorial: :func:`use_course`); every lesson of its catalog carries it
    (:attr:`ros2course.lesson.catalog.Lesson.course`), and the grading pipeline (the grader's package,
    the reference packages, the starters, the fingerprint of what a figure was measured on) reads the
    course from the lesson it grades, never from the process.

    Attributes:
        root: the course folder, resolved (no symlink left), so two spellings of one folder are one course.
    """

    root: Path

    def __post_init__(self) -> None:
        object.__setattr__(self, "root", Path(self.root).resolve())

    @property
    def graders(self) -> Path:
        """``graders/``: one grader module per lesson, imported as a package of its own
        (:func:`ros2course.grade.engine.graders_package`)."""
        return self.root / "graders"

    @property
    def chapters(self) -> Path:
        """``chapters/``: one ``<lesson id>/lesson.yaml`` folder per lesson, with its starter."""
        return self.root / "chapters"

    @property
    def solutions(self) -> Path:
        """``solutions/``: the reference workspace (``src/`` packages and the lessons' other folders)."""
        return self.root / "solutions"

    def manifest(self):  # -> ros2course.lesson.courses.CourseManifest (not imported here: see below)
        """The course's ``course.yaml``, validated (:func:`ros2course.lesson.courses.load_manifest`).

        Raises:
            CourseError: no manifest, or one that does not validate.
        """
        from ros2course.lesson.courses import load_manifest  # noqa: PLC0415 - pydantic only when asked (list's start time)

        return load_manifest(self.root)

    def catalog(self):  # -> ros2course.lesson.catalog.Catalog (same)
        """The course's lessons in order (:func:`ros2course.lesson.catalog.load_catalog`, cached per folder).

        Raises:
            LessonFormatError: a lesson file does not validate.
        """
        from ros2course.lesson.catalog import load_catalog  # noqa: PLC0415 - the catalog imports this module

        return load_catalog(self.root)


def active_course() -> Course:
    """The :class:`Course` of this command (:func:`content_root`'s folder): what the CLI chose, once."""
    return Course(content_root())
