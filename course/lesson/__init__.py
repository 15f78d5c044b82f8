"""The lesson catalog: lessons, starters, the learner's progress."""

from __future__ import annotations

import os
from pathlib import Path


def content_root() -> Path:
    """The folder holding ``chapters/``, ``graders/`` and ``solutions/``.

    ``ROS2COURSE_CONTENT`` overrides it (tests, instructors with their own course).
    Here rather than in :mod:`course.lesson.catalog` so ``list`` finds the course without pydantic.
    """
    override = os.environ.get("ROS2COURSE_CONTENT")
    return Path(override).resolve() if override else Path(__file__).resolve().parents[2]
