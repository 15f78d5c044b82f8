"""The learner's workspace: a colcon workspace (``src/``) with ``.ros2course/`` once ``ros2course init`` ran.

The progress file's schema (pydantic models) lives in :mod:`ros2course.lesson.progress`
and is imported only by the methods that read or write it with validation:
``list`` reads the file without pydantic (:mod:`ros2course.lesson.progress_view`) for its
start time (issue 13: under 0.25 s), and ``check`` records its attempt without it
(:func:`plain_progress`, :meth:`Workspace.record_attempt`; issue 36) whenever the
file's fields already have their declared types; one writer format for both
(:func:`progress_text`). Files are written atomically (temporary
file, fsync, ``os.replace``), so a check killed half-way never corrupts them
(rustlings keeps its state the same way).
"""

from __future__ import annotations

import contextlib
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

#: A lesson's record in the progress file: its fields in file order with their defaults (``LessonProgress``'s).
RECORD_FIELDS: dict[str, object] = {"best_score": None, "max_score": None, "last_status": None, "attempts": 0,
                                    "hints_shown": 0, "started": False}
#: The record's fields that are floats in ``LessonProgress`` (written as floats whoever writes the file).
_FLOAT_FIELDS = ("best_score", "max_score")


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


#: Each known field of a lesson's record and whether a value has the type ``LessonProgress`` declares.
RECORD_TYPES = {
    "best_score": lambda v: v is None or _is_number(v),
    "max_score": lambda v: v is None or _is_number(v),
    "last_status": lambda v: v is None or isinstance(v, str),
    "attempts": lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 0,
    "hints_shown": lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 0,
    "started": lambda v: isinstance(v, bool),
}


def plain_progress(data: object) -> dict | None:
    """A decoded progress file in the exact shape ``Progress`` writes (fields in order, defaults filled in,
    scores as floats, unknown keys dropped), when every known field already has its declared type; else
    None (the validating loader, :mod:`ros2course.lesson.progress`, then decides: it coerces or refuses).

    Read without pydantic: ``list`` and ``check`` read and record progress this way (issues 13 and 36).
    """
    if not isinstance(data, dict) or data.get("version", PROGRESS_VERSION) != PROGRESS_VERSION:
        return None
    current, course, lessons = data.get("current"), data.get("course"), data.get("lessons", {})
    if not (current is None or isinstance(current, str)) or not isinstance(lessons, dict):
        return None
    if course is not None and not (isinstance(course, dict) and isinstance(course.get("id"), str)
                                   and isinstance(course.get("version"), str)
                                   and (course.get("path") is None or isinstance(course.get("path"), str))):
        return None
    plain = {"version": PROGRESS_VERSION, "current": current,
             "course": None if course is None else {k: course.get(k) for k in ("id", "version", "path")},
             "lessons": {}}
    for lesson_id, record in lessons.items():
        if not isinstance(record, dict) or not all(check(record[key]) for key, check in RECORD_TYPES.items()
                                                   if key in record):
            return None
        entry = {key: record.get(key, default) for key, default in RECORD_FIELDS.items()}
        for key in _FLOAT_FIELDS:
            entry[key] = None if entry[key] is None else float(entry[key])
        plain["lessons"][lesson_id] = entry
    return plain


def progress_text(data: dict) -> str:
    """The progress file's text for ``data`` (a progress as JSON values): one format whoever writes it."""
    return json.dumps(data, indent=2, ensure_ascii=False) + "\n"


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
        atomic_write_text(self.progress_path, progress_text(progress.model_dump(mode="json")))

    def record_attempt(self, lesson_id: str, status: str, score: float, max_score: float) -> None:
        """Count one graded attempt of ``lesson_id`` (points) and keep the best score; saves the file.

        The file is re-read first, so an attempt recorded by another command
        meanwhile (``watch`` beside a ``check``) is not lost.
        """
        if not self.state_dir.is_dir():  # never init-ed: nothing to record (as save_progress)
            return
        plain = None
        with contextlib.suppress(OSError, ValueError):
            plain = plain_progress(json.loads(self.progress_path.read_text(encoding="utf-8")))
        if plain is None:  # no file, or one only the validating loader can read (it raises what is wrong)
            progress = self.load_progress()
            plain = progress.model_dump(mode="json")
        # as plain values: a check records its attempt without importing pydantic (~90 ms, issue 36)
        record = plain["lessons"].setdefault(lesson_id, dict(RECORD_FIELDS))
        record["attempts"] += 1
        record["last_status"] = status
        record["max_score"] = float(max_score)
        if record["best_score"] is None or score > record["best_score"]:
            record["best_score"] = float(score)
        atomic_write_text(self.progress_path, progress_text(plain))

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
