"""``ros2course list``'s table and the files column ``show`` prints too.

Kept apart from :mod:`ros2course.report.table` (results, plots, markdown) so
``list`` imports only rich (issue 13: start under 0.25 s). Rows are
:class:`ros2course.lesson.catalog.Lesson` (the kept catalog, read without pydantic).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from rich.console import Console
from rich.table import Table
from rich.text import Text

if TYPE_CHECKING:
    from ros2course.lesson.catalog import Lesson
    from ros2course.lesson.progress_view import ProgressView
    from ros2course.lesson.progress import Progress


def points_text(value: float) -> str:
    """Points as the shortest text (``3``, ``2.5``)."""
    return f"{value:g}"


def render_list(lessons: Sequence[Lesson], progress: ProgressView | Progress, console: Console,
                root: Path | None = None) -> None:
    """Every lesson with its status, best score and where its files are in the workspace ``root``.

    A path that exists is printed plain, one not made yet dim (``next`` copies
    the starter there).
    """
    table = Table(title="ros2course lessons", title_justify="left")
    table.add_column("#", justify="right")
    table.add_column("lesson", overflow="fold")  # ids are typed back: never cut them with an ellipsis
    table.add_column("title")
    table.add_column("status")
    table.add_column("best", justify="right")
    if root is not None:
        table.add_column("files", overflow="fold")
    styles = {"done": "green", "current": "bold cyan", "started": "yellow", "not started": "dim"}
    for index, lesson in enumerate(lessons, 1):
        status = progress.status(lesson.id)
        record = progress.lessons.get(lesson.id)
        best = (f"{points_text(record.best_score)}/{points_text(record.max_score)}"
                if record and record.best_score is not None and record.max_score is not None else "-")
        row = [str(index), lesson.id, lesson.title, Text(status, styles[status]), best]
        if root is not None:
            row.append(lesson_files(lesson, root))
        table.add_row(*row)
    console.print(table)


def lesson_files(lesson: Lesson, root: Path) -> Text:
    """The lesson's workspace paths (:attr:`Lesson.workspace_paths`), dim where not made yet."""
    text = Text()
    for index, relative in enumerate(lesson.workspace_paths):
        if index:
            text.append(", ")
        text.append(relative + ("/" if (root / relative).is_dir() else ""),
                    style="" if (root / relative).exists() else "dim")
    return text
