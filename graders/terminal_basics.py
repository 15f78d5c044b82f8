"""Grader for ``terminal-basics`` (seed ch. 1): files and folders made in a terminal.

Nothing is run: the grader looks at ``terminal_basics/`` in the learner's
workspace and reads a few small files there through :mod:`graders._files`.
It never reads anything outside that folder: a symbolic link whose target lies
outside it is reported (check ``stays_inside``) and not followed.

What the lesson asks for (LESSONS.md, "Preamble"), inside ``terminal_basics/``:

* ``a_folder/an_empty_file.txt``: an empty file in a folder (``mkdir``, ``touch``);
* ``file_with_stuff.txt``: the single word ``stuff`` (``nano`` or ``echo stuff >``);
* ``appended.txt``: the lines ``first line`` then ``second line``, each added with
  ``echo ... >> appended.txt`` (``>`` would have overwritten the first);
* ``result_of_ls.txt``: what ``ls`` prints in that folder (``ls > result_of_ls.txt``),
  matching the folder as it is when ``check`` runs.

Each file is its own part: a missing one ends only its own checks.
"""

from __future__ import annotations

import os
from pathlib import Path

from ros2course.kit import Check, Session, Unmet
from ros2course.kit import learner_files as files

#: No program is observed: the checks read files.
WINDOW = 0.0

#: The lesson's folder, relative to the workspace root.
FOLDER = "terminal_basics"
#: The two lines ``appended.txt`` must hold, in order.
APPENDED_LINES = ["first line", "second line"]

CHECKS = [
    Check("lesson_folder", "terminal_basics/ is a folder in the workspace", 1,
          "in the workspace folder run: mkdir terminal_basics"),
    Check("a_folder", "terminal_basics/a_folder/ is a folder", 1,
          "cd terminal_basics, then: mkdir a_folder", needs=("lesson_folder",), part="a_folder"),
    Check("empty_file", "a_folder/an_empty_file.txt exists and is empty", 1,
          "touch a_folder/an_empty_file.txt makes an empty file", needs=("a_folder",), part="a_folder"),
    Check("file_with_stuff", "file_with_stuff.txt contains the word stuff", 1,
          "nano file_with_stuff.txt, type stuff, then Ctrl+X, Y, Enter", needs=("lesson_folder",), part="stuff"),
    Check("appended", "appended.txt holds two lines added with >>", 2,
          "echo \"first line\" >> appended.txt, then echo \"second line\" >> appended.txt "
          "(rm appended.txt first if it holds anything else)",
          needs=("lesson_folder",), part="appended"),
    Check("result_of_ls", "result_of_ls.txt is what ls prints in terminal_basics/ now", 2,
          "as your last command, inside terminal_basics/, run: ls > result_of_ls.txt", needs=("lesson_folder",),
          part="listing"),
    Check("stays_inside", "No symbolic link in terminal_basics/ points outside it", 1,
          "make real files with touch, nano or echo instead of links (ln -s) to files elsewhere",
          needs=("lesson_folder",)),
]


def grade(s: Session) -> None:
    """Look at ``terminal_basics/`` and the files the chapter's commands make in it."""
    lesson = s.workspace_root / FOLDER
    expected = f"a folder {FOLDER}/ made with mkdir in the workspace folder"
    if lesson.is_symlink():
        problem = f"{FOLDER} is a symbolic link ({files.link_text(lesson)}); the grader reads only a real folder"
    elif not lesson.is_dir():
        problem = f"{lesson} is a file, not a folder" if lesson.exists() else f"there is no {FOLDER}/ in {s.workspace_root}"
    if lesson.is_symlink() or not lesson.is_dir():
        s.record("lesson_folder", False, problem, expected)
        raise Unmet(problem)
    s.record("lesson_folder", True, f"{FOLDER}/ exists", expected)
    real = Path(os.path.realpath(lesson))
    # stays_inside first: the file checks below refuse the same links, and say so
    outside = files.outside_links(real)
    s.record("stays_inside", not outside, "symbolic links leading out of the folder: " + "; ".join(outside)
             if outside else "no symbolic link leads out of the folder",
             f"everything the lesson makes lives inside {FOLDER}/")
    for part, judge in (("a_folder", _grade_a_folder), ("stuff", _grade_stuff), ("appended", _grade_appended),
                        ("listing", _grade_listing)):
        with s.part(part):
            judge(s, real)


def _grade_a_folder(s: Session, lesson: Path) -> None:
    """Checks ``a_folder`` and ``empty_file``."""
    expected = f"a folder {FOLDER}/a_folder/ (mkdir a_folder)"
    folder = files.entry(s, "a_folder", lesson / "a_folder", lesson, expected, kind="folder")
    s.record("a_folder", True, f"{FOLDER}/a_folder/ exists", expected)
    what = f"an empty file {FOLDER}/a_folder/an_empty_file.txt (touch makes one)"
    path = files.entry(s, "empty_file", folder / "an_empty_file.txt", lesson, what)
    size = path.stat().st_size
    s.record("empty_file", size == 0, "an_empty_file.txt exists and holds 0 bytes" if size == 0 else
             f"an_empty_file.txt holds {size} byte(s), starting {files.read_text(path)[:40]!r}", what,
             hint="empty means 0 bytes: 'echo > file' writes a newline; use touch (on a new file) or "
                  "'truncate -s 0 a_folder/an_empty_file.txt'")


def _grade_stuff(s: Session, lesson: Path) -> None:
    """Check ``file_with_stuff``: one line ``stuff`` (the final newline nano adds is optional)."""
    what = "file_with_stuff.txt holding the word stuff (one line; a final newline is fine)"
    text = files.read_text(files.entry(s, "file_with_stuff", lesson / "file_with_stuff.txt", lesson, what))
    s.record("file_with_stuff", [line.rstrip("\r") for line in text.splitlines()] == ["stuff"],
             f"file_with_stuff.txt holds {text[:80]!r}", what,
             hint=None if "stuff" not in text else "only the word stuff, on its own line, nothing else in the file")


def _grade_appended(s: Session, lesson: Path) -> None:
    """Check ``appended``: exactly the two lines of :data:`APPENDED_LINES`, in order."""
    first, second = APPENDED_LINES
    what = f"appended.txt holding two lines, {first!r} then {second!r} (each added with >>)"
    lines = files.lines(files.entry(s, "appended", lesson / "appended.txt", lesson, what))
    hint = None
    if lines == [second]:
        hint = (f"only {second!r} is left: the second command used > and overwrote the file. "
                f"rm appended.txt and add both lines with >>")
    elif len(lines) > 2 and lines[:2] == APPENDED_LINES:
        hint = "the lines were added more than once (>> keeps what is there): rm appended.txt and add each line once"
    shown = "; ".join(repr(line) for line in lines[:6]) + (" ..." if len(lines) > 6 else "")
    s.record("appended", lines == APPENDED_LINES, f"appended.txt holds {first!r} then {second!r}"
             if lines == APPENDED_LINES else f"appended.txt holds {len(lines)} line(s): {shown or 'nothing'}",
             what, hint=hint)


def _grade_listing(s: Session, lesson: Path) -> None:
    """Check ``result_of_ls``: the names in the file are the folder's names now.

    ``result_of_ls.txt`` itself may be listed or not: ``ls > result_of_ls.txt``
    lists it (the shell creates the file before ``ls`` runs), a listing written
    elsewhere and moved in does not.
    """
    own = "result_of_ls.txt"
    what = f"result_of_ls.txt listing exactly the names ls shows in {FOLDER}/ now ({own} itself may be among them)"
    lines = files.lines(files.entry(s, "result_of_ls", lesson / own, lesson, what))
    names = [line[:-1] if line.endswith("/") and len(line) > 1 else line for line in lines if line.strip()]
    listed = set(names)
    # plain ls lists each name once: a name twice is a listing appended to an older one (ls >> ..., helper audit)
    twice = sorted({name for name in names if names.count(name) > 1})
    # what plain ls shows: every entry except those whose names start with a dot
    present = {entry.name for entry in os.scandir(lesson) if not entry.name.startswith(".")}
    missing, extra = (present - {own}) - listed, listed - present
    # in ls's order: sorted by its locale's collation (letters and digits, case aside) or, under LANG=C, byte by
    # byte; ls -r, ls -t or a listing typed by hand in another order is not plain ls's output (audit of stop 71)
    in_order = names in (sorted(names), sorted(names, key=_collation))
    blank = any(not line.strip() for line in lines)  # plain ls writes no empty line
    long_format = any(line.startswith("total ") or (len(line) > 10 and line[0] in "-dl"
                                                    and not line[1:10].strip("rwxsStT-")) for line in lines)
    hint = None
    if long_format:
        observed = f"result_of_ls.txt holds {len(lines)} line(s) in ls -l's long format, e.g. {lines[-1][:80]!r}"
        hint = "the lesson asks for plain ls (names only): ls > result_of_ls.txt"
    else:
        details = ([f"not in the listing: {files.names(missing)}"] if missing else []) + (
            [f"listed but not in the folder: {files.names(extra)}"] if extra else []) + (
            [f"listed more than once: {files.names(twice)}"] if twice else []) + (
            [f"not in ls's sorted order: {', '.join(names)[:200]}"] if not in_order else []) + (
            ["an empty line among the names"] if blank else [])
        observed = f"result_of_ls.txt lists {files.names(listed)}; {FOLDER}/ holds {files.names(present)}" + (
            f" ({'; '.join(details)})" if details else ", which is what the folder holds")
        if missing and not extra:
            hint = ("the folder changed after you ran ls: run ls > result_of_ls.txt again, inside terminal_basics/, "
                    "as your last command")
        elif twice:
            hint = "> replaces the file's contents, >> adds to them: ls > result_of_ls.txt, as your last command"
        elif not in_order or blank:
            hint = "write the listing with plain ls, no options and nothing added: ls > result_of_ls.txt"
    s.record("result_of_ls", listed in (present, present - {own}) and not long_format and not twice and in_order
             and not blank, observed, what, hint=hint)


def _collation(name: str) -> tuple[str, str]:
    """A sort key close to ls's in an English UTF-8 locale (glibc's collation): letters and digits first, case
    aside, then the whole name as the tie-break."""
    return "".join(c for c in name.lower() if c.isalnum()), name
