"""Kit steps that read files a learner made, without ever following a link out of the lesson's folder.

For lessons whose result is files, not programs (tutorial ch. 1: ``mkdir``,
``touch``, ``echo >>``, ``ls >``; the cryptography lesson's keys and messages). A symbolic link whose target lies outside
the folder being graded is reported and never read: grading must not read
(or quote back) files elsewhere on the machine.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ros2course.kit import Session, Unmet

#: Largest file read, in bytes (the lessons' files are a few bytes long).
MAX_READ = 64 * 1024
#: Most entries looked at when searching a folder for symbolic links.
MAX_ENTRIES = 2000


def inside(path: Path, folder: Path) -> bool:
    """True when ``path``, with every symbolic link resolved, lies in ``folder`` (a resolved path)."""
    return Path(os.path.realpath(path)).is_relative_to(folder)


def link_text(path: Path) -> str:
    """``name -> target`` of a symbolic link, as ``ls -l`` shows it (the bare name if it cannot be read)."""
    try:
        return f"{path.name} -> {os.readlink(path)}"
    except OSError:
        return path.name


def outside_links(folder: Path) -> list[str]:
    """``<folder name>/...`` names of the symbolic links under ``folder`` (resolved) whose targets lie outside it.

    Walks without following links and stops after :data:`MAX_ENTRIES` entries.
    """
    found, seen = [], 0
    for top, dirs, files in os.walk(folder, followlinks=False):
        for name in sorted(dirs + files):
            seen += 1
            path = Path(top) / name
            if path.is_symlink() and not inside(path, folder):
                found.append(f"{path.relative_to(folder.parent)} -> {os.readlink(path)}")
            if seen >= MAX_ENTRIES:
                return found
    return found


def entry(s: Session, check_id: str, path: Path, folder: Path, what: str, *, kind: str = "file") -> Path:
    """``path`` resolved, when it is a regular file (``kind="file"``) or a folder (``kind="folder"``) inside ``folder``.

    Args:
        folder: the resolved folder being graded; a link leading out of it is refused before anything is read.
        what: the expected text of ``check_id``.

    Raises:
        Unmet: it is missing, a link out of ``folder``, or of the wrong kind; ``check_id`` is then recorded
            failed with what was found (the current part ends).
    """
    shown = f"{folder.name}/{path.relative_to(folder)}"
    if path.is_symlink() and not inside(path, folder):
        problem = (f"{shown} is a symbolic link to a place outside {folder.name}/ ({link_text(path)}); "
                   "the grader does not follow it")
    elif not path.exists():
        problem = f"there is no {shown}" + ("/" if kind == "folder" else "")
    else:
        try:
            mode = path.stat().st_mode
            problem = None if (stat.S_ISDIR(mode) if kind == "folder" else stat.S_ISREG(mode)) else (
                f"{shown} is a file, not a folder" if kind == "folder" else
                f"{shown} is {'a folder' if stat.S_ISDIR(mode) else 'not a regular file'}")
        except OSError as exc:
            problem = f"{shown} cannot be examined: {exc.strerror}"
    if problem is not None:
        s.record(check_id, False, problem, what)
        raise Unmet(problem)
    return Path(os.path.realpath(path))


def read_text(path: Path) -> str:
    """The first :data:`MAX_READ` bytes of ``path`` as text (undecodable bytes replaced)."""
    with path.open("rb") as handle:
        return handle.read(MAX_READ).decode("utf-8", errors="replace")


def lines(path: Path) -> list[str]:
    """The lines of :func:`read_text` without their line endings (``\\r\\n`` too)."""
    return [line.rstrip("\r") for line in read_text(path).splitlines()]


def names(found: set[str] | list[str], most: int = 12) -> str:
    """Names for feedback: ``a, b, c`` (each cut at 60 characters, at most ``most`` of them) or ``nothing``."""
    shown = sorted(found)
    text = ", ".join(name[:60] for name in shown[:most]) + (f" and {len(shown) - most} more" if len(shown) > most else "")
    return text or "nothing"
