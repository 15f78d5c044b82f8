"""One error base class and one table of exit codes for the whole tool.

Modelled on httpie's ``ExitStatus`` and click's exceptions-carry-their-exit-code
design (see shared/STYLE.md): every expected failure is a :class:`CourseError`
with a one-line message and a learner-facing hint; only ``ros2course.cli.main``
turns it into a process exit.
"""

from __future__ import annotations

import enum


class ExitStatus(enum.IntEnum):
    """Every exit code ``ros2course`` can return."""

    OK = 0
    #: ``check``: the submission was graded and lost points.
    CHECK_FAILED = 1
    #: Bad command line (typer's own usage errors also use 2).
    USAGE = 2
    #: ``check``: the submission could not be graded (build failed, nothing to run).
    NOT_GRADABLE = 3
    #: Something the command needs is not installed; ``ros2course doctor`` says what.
    MISSING_REQUIREMENT = 4
    #: No workspace, unknown lesson, malformed lesson file, corrupt progress file.
    BAD_INPUT = 5
    #: The grader itself failed; the result still lists it as "grader error".
    GRADER_ERROR = 6
    #: ``dev validate``: a lesson's reference, starter or wrong solutions misbehave.
    VALIDATION_FAILED = 7


class CourseError(Exception):
    """Base of every expected error: a one-line ``message`` plus a ``hint``.

    Args:
        message: what went wrong, one line, in the learner's terms.
        hint: what to do about it, one line (may be empty).
    """

    exit_status: ExitStatus = ExitStatus.BAD_INPUT

    def __init__(self, message: str, hint: str = "") -> None:
        super().__init__(message)
        self.message = message
        self.hint = hint


class WorkspaceNotFound(CourseError):
    """No initialised workspace at or above the given directory."""


class UnknownLesson(CourseError):
    """A lesson id that no ``chapters/*/lesson.yaml`` declares."""


class LessonFormatError(CourseError):
    """A lesson YAML file (or a fixture file) does not match the schema."""


class ProgressError(CourseError):
    """The progress file exists but cannot be read."""


class MissingRequirement(CourseError):
    """A tool or ROS package the command needs is not installed."""

    exit_status = ExitStatus.MISSING_REQUIREMENT


class NotGradable(CourseError):
    """The submission cannot be graded at all (e.g. it does not build)."""

    exit_status = ExitStatus.NOT_GRADABLE


class ValidationFailed(CourseError):
    """``ros2course dev validate`` found a lesson that misbehaves."""

    exit_status = ExitStatus.VALIDATION_FAILED
