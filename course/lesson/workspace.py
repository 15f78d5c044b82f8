"""The learner's workspace: a colcon workspace (``src/``) with ``.ros2course/`` once ``ros2course init`` ran.

The progress file's schema (pydantic models) lives in :mod:`ros2course.lesson.progress`
and is imported only by the methods that read or write it with validation:
``list`` reads the file without pydantic (:mod:`ros2course.lesson.index`) for its
start time (issue 13: under 0.25 s). Files are written atomically (temporary
file, fsync, ``os.replace``), so a check killed half-way never corrupts them
(rustlings keeps its state the same way).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

from ros2course.errors import ProgressError, WorkspaceNotFound
from ros2course.files import atomic_write_text
from ros2course.lesson.status import PROGRESS_VERSION

if TYPE_CHECKING:
    from ros2course.lesson.progress import Progress

STATE_DIR = ".ros2course"
PROGRESS_FILE = "progress.json"


class Workspace:
    """A colcon workspace, initialised by ``ros2course init`` or not.

    Args:
        root: the workspace folder (the one holding ``src/``).
    """

    def __init__(self, root: Path) -> None:
        self.root = root.resolve()

    @property
    def src(self) -> Path:
        return self.root / "src"

    @property
    def state_dir(self) -> Path:
        return self.root / STATE_DIR

    @property
    def progress_path(self) -> Path:
        return self.state_dir / PROGRESS_FILE

    @property
    def initialised(self) -> bool:
        """True when ``ros2course init`` ran here (a progress file exists)."""
        return self.progress_path.is_file()

    def load_progress(self) -> Progress:
        """Read and validate the progress file (an empty :class:`~ros2course.lesson.progress.Progress` if none).

        Raises:
            ProgressError: the file is not valid JSON or not a known version.
        """
        from pydantic import ValidationError  # noqa: PLC0415 - start time of list (module docstring)

        from ros2course.lesson.progress import Progress  # noqa: PLC0415 - same

        if not self.progress_path.is_file():
            return Progress()
        try:
            data = json.loads(self.progress_path.read_text(encoding="utf-8"))
            progress = Progress.model_validate(data)
        except (OSError, json.JSONDecodeError, ValidationError) as exc:
            raise ProgressError(f"{self.progress_path}: unreadable progress file ({str(exc).splitlines()[0]})",
                                "move it away and run 'ros2course init' again; your code is not touched") from exc
        if progress.version != PROGRESS_VERSION:
            raise ProgressError(f"{self.progress_path}: progress file version {progress.version} is not supported",
                                f"this ros2course reads version {PROGRESS_VERSION}; upgrade ros2course")
        return progress

    def course_record(self) -> dict | None:
        """The ``course`` record of the progress file (``{"id", "version", "path"}``), read without pydantic.

        None when the workspace records no course (made before courses were recorded, or never
        ``init``-ed) or the file cannot be read (:meth:`load_progress` reports that).
        """
        try:
            record = json.loads(self.progress_path.read_text(encoding="utf-8")).get("course")
        except (OSError, ValueError, AttributeError):
            return None
        return record if isinstance(record, dict) and isinstance(record.get("id"), str) else None

    def record_course(self, course_id: str, version: str, path: Path) -> None:
        """Record the course this workspace follows (its id, version and folder); saves the file."""
        from ros2course.lesson.progress import CourseRecord  # noqa: PLC0415 - start time of list (module docstring)

        progress = self.load_progress()
        progress.course = CourseRecord(id=course_id, version=version, path=str(path))
        self.save_progress(progress)

    def save_progress(self, progress: Progress) -> None:
        """Write the progress file atomically (no-op for a workspace never ``init``-ed)."""
        if not self.state_dir.is_dir():
            return
        atomic_write_text(self.progress_path, progress.model_dump_json(indent=2) + "\n")

    def record_attempt(self, lesson_id: str, status: str, score: float, max_score: float) -> None:
        """Count one graded attempt of ``lesson_id`` (points) and keep the best score; saves the file.

        The file is re-read first, so an attempt recorded by another command
        meanwhile (``watch`` beside a ``check``) is not lost.
        """
        progress = self.load_progress()
        record = progress.lesson(lesson_id)
        record.attempts += 1
        record.last_status = status
        record.max_score = max_score
        if record.best_score is None or score > record.best_score:
            record.best_score = score
        self.save_progress(progress)

    def init(self) -> bool:
        """Create ``src/`` and the progress file; returns False if it already existed.

        Raises:
            WorkspaceNotFound: the folder cannot be made (a file is in the way, no permission).
        """
        try:
            self.src.mkdir(parents=True, exist_ok=True)
            if self.initialised:
                return False
            self.state_dir.mkdir(parents=True, exist_ok=True)
            atomic_write_text(self.state_dir / ".gitignore", "backups/\n")
            from ros2course.lesson.progress import Progress  # noqa: PLC0415 - start time of list (module docstring)

            self.save_progress(Progress())
        except (FileExistsError, NotADirectoryError) as exc:
            raise WorkspaceNotFound(f"cannot create a workspace at {self.root}: {exc.filename} is a file, not a folder",
                                    "choose another folder, or move that file away") from exc
        except PermissionError as exc:
            raise WorkspaceNotFound(f"cannot create a workspace at {self.root}: permission denied ({exc.filename})",
                                    "choose a folder you can write to, e.g. under your home folder") from exc
        return True


def find_workspace(start: Path | None = None, explicit: Path | None = None) -> Workspace:
    """The workspace to work on.

    Args:
        start: where to search upwards from (default: the current directory).
        explicit: ``--workspace DIR``; must exist and have ``src/`` (need not be ``init``-ed).

    Raises:
        WorkspaceNotFound: nothing suitable, with a hint to ``init`` or pass ``--workspace``.
    """
    if explicit is not None:
        if not explicit.is_dir():
            raise WorkspaceNotFound(f"workspace {explicit} does not exist", "create it with 'ros2course init DIR'")
        ws = Workspace(explicit)
        if not ws.src.is_dir() and not ws.initialised:
            raise WorkspaceNotFound(f"{explicit} is not a colcon workspace (no src/ folder)",
                                    "pass the folder that holds src/, or run 'ros2course init DIR'")
        return ws
    here = (start or Path.cwd()).resolve()
    for folder in (here, *here.parents):
        if (folder / STATE_DIR / PROGRESS_FILE).is_file():
            return Workspace(folder)
    raise WorkspaceNotFound(f"no ros2course workspace at or above {here}",
                            "run 'ros2course init ros2_tutorial_workspace' or pass --workspace DIR")
