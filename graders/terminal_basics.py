"""Grader for ``terminal-basics`` (seed ch. 1): files and folders made in a terminal.

Nothing is run: the grader looks at ``terminal_basics/`` in the learner's
workspace and reads a few small files there. It never reads anything outside
that folder: a symbolic link whose target lies outside it is reported (check
``stays_inside``) and not followed.

What the lesson asks for (LESSONS.md, "Preamble"), inside ``terminal_basics/``:

* ``a_folder/an_empty_file.txt``: an empty file in a folder (``mkdir``, ``touch``);
* ``file_with_stuff.txt``: the single word ``stuff`` (``nano`` or ``echo stuff >``);
* ``appended.txt``: the lines ``first line`` then ``second line``, each added with
  ``echo ... >> appended.txt`` (``>`` would have overwritten the first);
* ``result_of_ls.txt``: what ``ls`` prints in that folder (``ls > result_of_ls.txt``),
  matching the folder as it is when ``check`` runs.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from graders.kit import Check, GradingSession, Unmet

#: No program is observed: the checks read files.
WINDOW = 0.0

#: The lesson's folder, relative to the workspace root.
FOLDER = "terminal_basics"
#: The two lines ``appended.txt`` must hold, in order.
APPENDED_LINES = ("first line", "second line")
#: Largest file the grader reads (bytes); the lesson's files are a few bytes long.
MAX_READ = 64 * 1024
#: Most entries looked at when searching the folder for symbolic links.
MAX_ENTRIES = 2000

CHECKS = [
    Check("lesson_folder", "terminal_basics/ is a folder in the workspace", 1,
          "in the workspace folder run: mkdir terminal_basics"),
    Check("a_folder", "terminal_basics/a_folder/ is a folder", 1,
          "cd terminal_basics, then: mkdir a_folder", needs=("lesson_folder",)),
    Check("empty_file", "a_folder/an_empty_file.txt exists and is empty", 1,
          "touch a_folder/an_empty_file.txt makes an empty file", needs=("a_folder",)),
    Check("file_with_stuff", "file_with_stuff.txt contains the word stuff", 1,
          "nano file_with_stuff.txt, type stuff, then Ctrl+X, Y, Enter", needs=("lesson_folder",)),
    Check("appended", "appended.txt holds two lines added with >>", 2,
          "echo \"first line\" >> appended.txt, then echo \"second line\" >> appended.txt "
          "(rm appended.txt first if it holds anything else)",
          needs=("lesson_folder",)),
    Check("result_of_ls", "result_of_ls.txt is what ls prints in terminal_basics/ now", 2,
          "as your last command, inside terminal_basics/, run: ls > result_of_ls.txt", needs=("lesson_folder",)),
    Check("stays_inside", "No symbolic link in terminal_basics/ points outside it", 1,
          "make real files with touch, nano or echo instead of links (ln -s) to files elsewhere",
          needs=("lesson_folder",)),
]


def _inside(path: Path, folder: Path) -> bool:
    """True when ``path``, with every symbolic link resolved, lies in ``folder`` (a resolved path)."""
    return Path(os.path.realpath(path)).is_relative_to(folder)


def _link_text(path: Path) -> str:
    """``name -> target`` of a symbolic link, as ``ls -l`` shows it."""
    try:
        return f"{path.name} -> {os.readlink(path)}"
    except OSError:
        return path.name


def _outside_links(folder: Path) -> list[str]:
    """Workspace-relative names of the symbolic links under ``folder`` whose targets lie outside it.

    Walks without following links and stops after :data:`MAX_ENTRIES` entries.
    """
    found, seen = [], 0
    for top, dirs, files in os.walk(folder, followlinks=False):
        for name in sorted(dirs + files):
            seen += 1
            path = Path(top) / name
            if path.is_symlink() and not _inside(path, folder):
                found.append(f"{path.relative_to(folder.parent)} -> {os.readlink(path)}")
            if seen >= MAX_ENTRIES:
                return found
    return found


def _regular_file(s: GradingSession, check_id: str, path: Path, folder: Path, what: str) -> Path | None:
    """``path`` resolved when it is a regular file inside ``folder``; else records ``check_id`` failed, returns None."""
    shown = f"{FOLDER}/{path.relative_to(folder)}"
    # the link test comes first: nothing outside the folder is even looked at
    if path.is_symlink() and not _inside(path, folder):
        s.record(check_id, False, f"{shown} is a symbolic link to a place outside {FOLDER}/ "
                 f"({_link_text(path)}); the grader does not follow it", what + f" (a real file inside {FOLDER}/)")
        return None
    if not path.exists() and not path.is_symlink():
        s.record(check_id, False, f"there is no {shown}", what)
        return None
    try:
        mode = path.stat().st_mode
    except OSError as exc:
        s.record(check_id, False, f"{shown} cannot be examined: {exc.strerror}", what)
        return None
    if not stat.S_ISREG(mode):
        kind = "a folder" if stat.S_ISDIR(mode) else "not a regular file"
        s.record(check_id, False, f"{shown} is {kind}", what)
        return None
    return Path(os.path.realpath(path))


def _read(path: Path) -> str:
    """The first :data:`MAX_READ` bytes of ``path`` as text (undecodable bytes replaced)."""
    with path.open("rb") as handle:
        return handle.read(MAX_READ).decode("utf-8", errors="replace")


def _names(names: set[str] | list[str]) -> str:
    """Names for feedback: ``a, b, c`` or ``nothing``."""
    shown = sorted(names)
    text = ", ".join(name[:60] for name in shown[:12]) + (f" and {len(shown) - 12} more" if len(shown) > 12 else "")
    return text or "nothing"


def grade(s: GradingSession) -> None:
    """Look at ``terminal_basics/`` and the files the chapter's commands make in it."""
    lesson = s.workspace_root / FOLDER
    if lesson.is_symlink():
        s.record("lesson_folder", False, f"{FOLDER} is a symbolic link ({_link_text(lesson)}); the grader reads "
                 "only a real folder in the workspace", f"a folder {FOLDER}/ made with mkdir in the workspace")
        raise Unmet(f"{FOLDER} is a symbolic link")
    if not lesson.is_dir():
        observed = f"{lesson} is a file, not a folder" if lesson.exists() else f"there is no {FOLDER}/ in {s.workspace_root}"
        s.record("lesson_folder", False, observed, f"a folder {FOLDER}/ in the workspace folder")
        raise Unmet(f"there is no folder {FOLDER}/")
    s.record("lesson_folder", True, f"{FOLDER}/ exists", f"a folder {FOLDER}/ in the workspace folder")
    real = Path(os.path.realpath(lesson))

    # stays_inside first: the file checks below refuse the same links, and say so
    outside = _outside_links(real)
    s.record("stays_inside", not outside,
             "symbolic links leading out of the folder: " + "; ".join(outside) if outside
             else "no symbolic link leads out of the folder",
             f"everything the lesson makes lives inside {FOLDER}/")

    _grade_a_folder(s, real)
    _grade_stuff(s, real)
    _grade_appended(s, real)
    _grade_listing(s, real)


def _grade_a_folder(s: GradingSession, lesson: Path) -> None:
    """Checks ``a_folder`` and ``empty_file``."""
    folder = lesson / "a_folder"
    expected = f"a folder {FOLDER}/a_folder/ (mkdir a_folder)"
    if folder.is_symlink() and not _inside(folder, lesson):
        s.record("a_folder", False, f"{FOLDER}/a_folder is a symbolic link to a place outside {FOLDER}/ "
                 f"({_link_text(folder)}); the grader does not follow it", expected)
        return
    if not folder.is_dir():
        s.record("a_folder", False, f"{FOLDER}/a_folder is a file, not a folder" if folder.exists()
                 else f"there is no {FOLDER}/a_folder/", expected)
        return
    s.record("a_folder", True, f"{FOLDER}/a_folder/ exists", expected)
    what = f"an empty file {FOLDER}/a_folder/an_empty_file.txt (touch makes one)"
    path = _regular_file(s, "empty_file", folder / "an_empty_file.txt", lesson, what)
    if path is None:
        return
    size = path.stat().st_size
    if size == 0:
        s.record("empty_file", True, "an_empty_file.txt exists and holds 0 bytes", what)
        return
    head = _read(path)[:40]
    s.record("empty_file", False, f"an_empty_file.txt holds {size} byte(s), starting {head!r}", what,
             hint="empty means 0 bytes: 'echo > file' writes a newline; use touch (on a new file) or "
                  "'truncate -s 0 a_folder/an_empty_file.txt'")


def _grade_stuff(s: GradingSession, lesson: Path) -> None:
    """Check ``file_with_stuff``: one line ``stuff`` (the final newline nano adds is optional)."""
    what = "file_with_stuff.txt holding the word stuff (one line; a final newline is fine)"
    path = _regular_file(s, "file_with_stuff", lesson / "file_with_stuff.txt", lesson, what)
    if path is None:
        return
    text = _read(path)
    lines = [line.rstrip("\r") for line in text.splitlines()]
    ok = lines == ["stuff"]
    s.record("file_with_stuff", ok, f"file_with_stuff.txt holds {text[:80]!r}", what,
             hint=None if "stuff" not in text else "only the word stuff, on its own line, nothing else in the file")


def _grade_appended(s: GradingSession, lesson: Path) -> None:
    """Check ``appended``: exactly the two lines of :data:`APPENDED_LINES`, in order."""
    first, second = APPENDED_LINES
    what = f"appended.txt holding two lines, {first!r} then {second!r} (each added with >>)"
    path = _regular_file(s, "appended", lesson / "appended.txt", lesson, what)
    if path is None:
        return
    text = _read(path)
    lines = [line.rstrip("\r") for line in text.splitlines()]
    if lines == list(APPENDED_LINES):
        s.record("appended", True, f"appended.txt holds {first!r} then {second!r}", what)
        return
    hint = None
    if lines == [second]:
        hint = (f"only {second!r} is left: the second command used > and overwrote the file. "
                f"rm appended.txt and add both lines with >>")
    elif len(lines) > 2 and lines[:2] == list(APPENDED_LINES):
        hint = "the lines were added more than once (>> keeps what is there): rm appended.txt and add each line once"
    shown = "; ".join(repr(line) for line in lines[:6]) + (" ..." if len(lines) > 6 else "")
    s.record("appended", False, f"appended.txt holds {len(lines)} line(s): {shown or 'nothing'}", what, hint=hint)


def _grade_listing(s: GradingSession, lesson: Path) -> None:
    """Check ``result_of_ls``: the names in the file are the folder's names now.

    ``result_of_ls.txt`` itself may be listed or not: ``ls > result_of_ls.txt``
    lists it (the shell creates the file before ``ls`` runs), a listing written
    elsewhere and moved in does not.
    """
    own = "result_of_ls.txt"
    what = f"result_of_ls.txt listing exactly the names ls shows in {FOLDER}/ now ({own} itself may be among them)"
    path = _regular_file(s, "result_of_ls", lesson / own, lesson, what)
    if path is None:
        return
    lines = [line.rstrip("\r") for line in _read(path).splitlines()]
    listed = {line[:-1] if line.endswith("/") and len(line) > 1 else line for line in lines if line.strip()}
    # what plain ls shows: every entry except those whose names start with a dot
    present = {entry.name for entry in os.scandir(lesson) if not entry.name.startswith(".")}
    ok = listed in (present, present - {own})
    if ok:
        s.record("result_of_ls", True, f"result_of_ls.txt lists {_names(listed)}, which is what the folder holds", what)
        return
    if any(line.startswith("total ") or (len(line) > 10 and line[0] in "-dl" and not line[1:10].strip("rwxsStT-"))
           for line in lines):
        s.record("result_of_ls", False, f"result_of_ls.txt holds {len(lines)} line(s) in ls -l's long format, "
                 f"e.g. {lines[-1][:80]!r}", what,
                 hint="the lesson asks for plain ls (names only): ls > result_of_ls.txt")
        return
    missing, extra = (present - {own}) - listed, listed - present
    details = []
    if missing:
        details.append(f"not in the listing: {_names(missing)}")
    if extra:
        details.append(f"listed but not in the folder: {_names(extra)}")
    hint = None
    if missing and not extra:
        hint = ("the folder changed after you ran ls: run ls > result_of_ls.txt again, inside terminal_basics/, "
                "as your last command")
    s.record("result_of_ls", False, f"result_of_ls.txt lists {_names(listed)}; {FOLDER}/ holds {_names(present)} ("
             + "; ".join(details) + ")", what, hint=hint)
