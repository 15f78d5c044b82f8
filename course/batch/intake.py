"""Intake: what a learning management system hands the instructor, turned into a submissions folder (issue 39).

``ros2course grade`` grades a folder with one entry per student, named by the
student id (:mod:`ros2course.batch.archive`). :func:`intake` makes that folder
(``staging/submissions/``) from a download of Canvas, Moodle or Blackboard, or from
a folder of git clones, and writes ``staging/intake.json``: one :class:`IntakeRecord` per
student (who, from which member, when submitted, late per the LMS, the commit,
or why not taken). :func:`load_intake` reads it back (late policies read
``submitted_at`` from it).

Safety, the same rules as :mod:`ros2course.batch.archive` (its helpers are
used, not copied): a download member with an absolute or ``..`` name, a
symbolic link, a device file or fifo, more than :data:`~ros2course.batch.archive.MAX_MEMBERS`
members or :data:`~ros2course.batch.archive.MAX_UNPACKED_BYTES` bytes for one
student, or a member unpacking to more than it declares makes that student's
record carry the reason; the rest of the class is taken. A student's own
archive is extracted by :func:`~ros2course.batch.archive.extract_zip` /
:func:`~ros2course.batch.archive.extract_tar`. Nothing is written outside
``staging`` and nothing ever into ``source``.
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
import shutil
import stat
import subprocess
import zipfile
from collections import defaultdict
from collections.abc import Callable, Iterator
from datetime import datetime, timezone, tzinfo
from pathlib import Path
from typing import IO

from pydantic import BaseModel

from ros2course.batch.archive import (
    ARCHIVE_SUFFIXES,
    MAX_MEMBERS,
    MAX_UNPACKED_BYTES,
    _member_ok,
    discover,
    extract_tar,
    extract_zip,
    student_id,
)
from ros2course.errors import CourseError, NotGradable
from ros2course.files import atomic_write_text

#: The formats :func:`intake` reads.
FORMATS = ("folder", "canvas", "moodle", "blackboard", "git")
#: The folder of ``staging`` that holds the entries, one per student: the folder graded. The manifest sits beside
#: it, not in it: :func:`ros2course.batch.archive.discover` would list ``intake.json`` as a student's entry.
ENTRIES = "submissions"
#: The manifest's file name inside ``staging``.
MANIFEST = "intake.json"
#: Members a whole class download may hold (the per-student cap is ``MAX_MEMBERS``).
CLASS_MAX_MEMBERS = 50 * MAX_MEMBERS
#: Seconds one git command of a clone may take.
GIT_TIMEOUT = 120.0

# Canvas, "Download Submissions" of an assignment: a flat zip, one file per submitted attachment, named
# ``<lastfirst>_<userid>_<submissionid>_<original name>``, ``<lastfirst>_LATE_<userid>_<submissionid>_<name>``
# when submitted after the due date; Canvas appends ``-N`` to the original name (before its extension) when a
# student's files share a name, so they stay apart. Documented by Instructure's guide "How do I download all
# student submissions for an assignment?" (community.canvaslms.com, Canvas Instructor Guide) and seen in
# downloads, e.g. https://github.com/mikewesthad/canvas-unzipper (README: smithbob_340934_208490284_BobsWork.zip).
_CANVAS = re.compile(r"^(?P<name>[^_/]+)_(?:(?P<late>LATE)_)?(?P<uid>\d+)_(?P<sub>\d+)_(?P<file>[^/]+)$")
# Moodle, "Download all submissions" (mod/assign): with "Download submissions in folders" (the default since
# Moodle 3.x, MDL-62831) one folder per participant ``<Full Name>_<participantid>_assignsubmission_file_/`` with
# the student's files and sub-folders as uploaded; older sites, flat files
# ``<Full Name>_<participantid>_assignsubmission_file_<filename>``. Moodle's help string ``downloadasfolders_help``
# (mod/assign/lang/en/assign.php, https://github.com/moodle/moodle/commit/381bb721538cbba98ac84447a6da22fdb4dc94a2).
# Other submission plugins (``assignsubmission_onlinetext_``) are left out: they hold no code.
_MOODLE = re.compile(r"^(?P<name>.+?)_(?P<pid>\d+)_assignsubmission_(?P<plugin>[a-z0-9]+)_(?P<rest>.*)$")
# Blackboard Learn, Grade Centre "Assignment File Download": a flat zip,
# ``<Assignment>_<username>_attempt_<YYYY-MM-DD-HH-MM-SS>_<original name>`` per file plus a receipt
# ``<Assignment>_<username>_attempt_<stamp>.txt`` ("Name: First Last (username)", "Date Submitted: ..."). Blackboard
# help "Download assignments" (help.blackboard.com, Learn Original, Grade Centre) and nbgrader's documented
# Blackboard collector (https://nbgrader.readthedocs.io, "Exchanging assignment files manually":
# ``ps1_hacker_attempt_2016-01-30-20-30-10_problem1.ipynb``). Usernames hold no ``_`` here (Blackboard's own
# usernames are the institution's login names).
_BLACKBOARD = re.compile(r"^(?P<assign>.+)_(?P<user>[^_/]+)_attempt_(?P<stamp>\d{4}(?:-\d{2}){5})"
                         r"(?:_(?P<file>[^/]+)|(?P<receipt>\.txt))$")
_RECEIPT_NAME = re.compile(r"^\s*Name:\s*(?P<name>.*?)\s*\((?P<user>[^()]*)\)\s*$", re.MULTILINE)
_NAMING = {
    "canvas": "<lastfirst>_[LATE_]<userid>_<submissionid>_<file>",
    "moodle": "<Full Name>_<participantid>_assignsubmission_file_/ (or ..._assignsubmission_file_<file>)",
    "blackboard": "<Assignment>_<username>_attempt_<YYYY-MM-DD-HH-MM-SS>_<file> (+ .txt receipt)",
}
_LMS_NAMES = {"canvas": "Canvas", "moodle": "Moodle", "blackboard": "Blackboard"}


class IntakeRecord(BaseModel):
    """One student of an intake (a line of ``staging/intake.json``).

    Attributes:
        student: the student id, safe for a folder name (:func:`ros2course.batch.archive.student_id`): the
            Canvas user id, the Moodle participant id, the Blackboard username, the clone's or entry's name.
            An LMS member whose name cannot be mapped gets ``unmapped_<member name>``.
        name: the student's name as the LMS gives it (Canvas ``lastfirst``, Moodle full name, Blackboard
            receipt's name), or None.
        source: the member(s) of the download (``; ``-separated) or the path the entry came from.
        submitted_at: when submitted, ISO 8601 with its UTC offset (Blackboard attempt stamp, git commit's
            committer date), or None when the source does not say (Canvas, Moodle, folder).
        lms_late: True / False when the LMS marks late submissions in its names (Canvas), else None.
        commit: the full hash of the commit taken (git), else None.
        problem: why the student was not taken (not gradable), or None when the entry was staged.
    """

    student: str
    name: str | None = None
    source: str
    submitted_at: str | None = None
    lms_late: bool | None = None
    commit: str | None = None
    problem: str | None = None


@dataclasses.dataclass
class IntakeReport:
    """What :func:`intake` did.

    Attributes:
        fmt: the format read (one of :data:`FORMATS`).
        source: the download or folder read (absolute).
        staging: the folder written (absolute): ``intake.json`` and the entries' folder ``submissions/``.
        folder: the submissions folder to grade: ``staging/submissions`` (``source`` for ``folder``, which is not
            copied).
        records: student id -> record, sorted by student id.
    """

    fmt: str
    source: Path
    staging: Path
    folder: Path
    records: dict[str, IntakeRecord]

    @property
    def taken(self) -> list[str]:
        """Student ids staged (no problem)."""
        return [sid for sid, rec in self.records.items() if rec.problem is None]

    @property
    def problems(self) -> dict[str, str]:
        """Student id -> why not taken."""
        return {sid: rec.problem for sid, rec in self.records.items() if rec.problem is not None}


# --- members of a download (a zip or its unpacked folder) ------------------------------------------------------

@dataclasses.dataclass
class _Member:
    """One file of a download: its posix name, declared size (bytes), why refused ("" when fine), an opener."""

    name: str
    size: int
    problem: str
    open: Callable[[], IO[bytes]] | None


def _zip_members(zf: zipfile.ZipFile) -> Iterator[_Member]:
    infos = zf.infolist()
    if len(infos) > CLASS_MAX_MEMBERS:
        raise CourseError(f"the download has {len(infos)} members (at most {CLASS_MAX_MEMBERS})",
                          "download the submissions in smaller groups of students")
    for info in infos:
        if info.is_dir() or _os_litter(info.filename):
            continue
        mode = info.external_attr >> 16
        problem = _member_ok(info.filename)
        if not problem and stat.S_ISLNK(mode):
            problem = f"{info.filename!r} is a symbolic link"
        elif not problem and stat.S_IFMT(mode) and not stat.S_ISREG(mode):
            problem = f"{info.filename!r} is a device, fifo or socket"
        yield _Member(info.filename.replace("\\", "/"), info.file_size, problem,
                      None if problem else (lambda info=info: zf.open(info)))


def _os_litter(name: str) -> bool:
    """What a desktop adds when it re-zips a download (macOS ``__MACOSX/``, ``.DS_Store``): left out unread."""
    parts = name.replace("\\", "/").split("/")
    return parts[0] == "__MACOSX" or parts[-1] in (".DS_Store", "Thumbs.db")


def _folder_members(root: Path) -> Iterator[_Member]:
    """Every file below ``root`` (an unpacked download); links and special files come back refused, unfollowed."""
    count = 0
    for dirpath, dirs, files in os.walk(root, followlinks=False):
        here = Path(dirpath)
        for d in list(dirs):
            if (here / d).is_symlink():
                dirs.remove(d)
                files.append(d)
        dirs.sort()
        for fname in sorted(files):
            count += 1
            if count > CLASS_MAX_MEMBERS:
                raise CourseError(f"the download has more than {CLASS_MAX_MEMBERS} files",
                                  "download the submissions in smaller groups of students")
            path = here / fname
            rel = path.relative_to(root).as_posix()
            if rel.split("/")[0].startswith(".") or _os_litter(rel):
                continue
            st = path.lstat()
            if stat.S_ISLNK(st.st_mode):
                yield _Member(rel, 0, f"{rel!r} is a symbolic link", None)
            elif not stat.S_ISREG(st.st_mode):
                yield _Member(rel, 0, f"{rel!r} is a device, fifo or socket", None)
            else:
                yield _Member(rel, st.st_size, "", lambda path=path: open(path, "rb"))


def _copy_member(member: _Member, target: Path) -> int:
    """Stream ``member`` to ``target``, stopping past its declared size (a zip bomb); returns bytes written.

    Raises:
        NotGradable: the member unpacks to more than it declares, or cannot be read.
    """
    assert member.open is not None
    written = 0
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        with member.open() as src, open(target, "xb") as out:
            while chunk := src.read(1 << 20):
                written += len(chunk)
                if written > member.size or written > MAX_UNPACKED_BYTES:
                    raise NotGradable(f"{member.name!r} unpacks to more than its declared size")
                out.write(chunk)
    except NotGradable:
        raise
    except (OSError, zipfile.BadZipFile, EOFError, RuntimeError, ValueError, NotImplementedError) as exc:
        raise NotGradable(f"{member.name!r} cannot be read: {type(exc).__name__}: {exc}") from exc
    return written


# --- one student's files -> one staged entry ---------------------------------------------------------------------

@dataclasses.dataclass
class _Student:
    """One student's part of a download, gathered before anything is written."""

    raw_id: str
    name: str | None = None
    files: list[tuple[str, _Member]] = dataclasses.field(default_factory=list)  # (path inside the entry, member)
    sources: list[str] = dataclasses.field(default_factory=list)
    submitted_at: str | None = None
    lms_late: bool | None = None
    problem: str = ""


def _is_archive(name: str) -> bool:
    return name.lower().endswith(ARCHIVE_SUFFIXES)


def _stage_files(student: _Student, entry: Path, scratch: Path) -> None:
    """Write ``student``'s files into ``entry`` (a new folder).

    One archive at the top of the student's files is their workspace: it is extracted into ``entry``; several
    are extracted each into ``entry/<archive stem>/``. Every other file is placed as is, at its path.

    Raises:
        NotGradable: a refused member, too many members or bytes, an unsafe or unreadable archive, two files
            landing on one path.
    """
    for rel, member in student.files:
        if member.problem:
            raise NotGradable(f"unsafe download member: {member.problem}")
        if _member_ok(rel) or rel in (".", ""):
            raise NotGradable(f"unsafe download member: {member.name!r} names the file {rel!r}")
    if len(student.files) > MAX_MEMBERS:
        raise NotGradable(f"{len(student.files)} files (at most {MAX_MEMBERS})")
    declared = sum(member.size for _rel, member in student.files)
    if declared > MAX_UNPACKED_BYTES:
        raise NotGradable(f"the files hold more than {MAX_UNPACKED_BYTES} bytes")
    archives = [(rel, m) for rel, m in student.files if "/" not in rel and _is_archive(rel)]
    entry.mkdir(parents=True)
    for rel, member in student.files:
        if "/" not in rel and _is_archive(rel):
            continue
        target = entry / rel
        if target.exists():
            raise NotGradable(f"two files land on {rel!r}")
        _copy_member(member, target)
    for rel, member in archives:
        dest = entry if len(archives) == 1 else entry / student_id(rel)
        copy = scratch / f"{student_id(student.raw_id)}-{student_id(rel)}{_suffix(rel)}"
        try:
            _copy_member(member, copy)
            dest.mkdir(parents=True, exist_ok=True)
            (extract_zip if rel.lower().endswith(".zip") else extract_tar)(copy, dest)
        finally:
            copy.unlink(missing_ok=True)


def _suffix(name: str) -> str:
    return next(s for s in ARCHIVE_SUFFIXES if name.lower().endswith(s))


def _stage_students(students: dict[str, _Student], staging: Path, records: dict[str, IntakeRecord]) -> None:
    """Stage every student of ``students`` (raw id -> files) into ``staging/submissions``; a record each."""
    scratch = staging / ".intake-scratch"
    scratch.mkdir(exist_ok=True)
    try:
        for raw in sorted(students):
            student = students[raw]
            sid = student_id(raw)
            problem = student.problem
            if sid in records:
                problem = f"duplicate student id {sid!r} (from {raw!r})"
                sid = student_id(f"{sid}__{raw}__dup{len(records)}")
            if not problem:
                entry = staging / ENTRIES / sid
                try:
                    if not student.files:
                        raise NotGradable("no file submitted")
                    _stage_files(student, entry, scratch)
                except NotGradable as exc:
                    problem = exc.message
                    shutil.rmtree(entry, ignore_errors=True)
            records[sid] = IntakeRecord(student=sid, name=student.name, source="; ".join(student.sources),
                                        submitted_at=student.submitted_at, lms_late=student.lms_late,
                                        problem=problem or None)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


# --- the LMS formats ---------------------------------------------------------------------------------------------

def _unmapped(member: _Member, fmt: str) -> IntakeRecord:
    sid = student_id(f"unmapped_{member.name}")
    why = member.problem or f"{member.name!r} does not follow {_LMS_NAMES[fmt]}'s naming {_NAMING[fmt]}"
    return IntakeRecord(student=sid, source=member.name, problem=why)


def _map_canvas(members: list[_Member]) -> tuple[dict[str, _Student], list[_Member]]:
    students: dict[str, _Student] = {}
    unmapped: list[_Member] = []
    for member in members:
        m = _CANVAS.match(member.name)
        if not m:
            unmapped.append(member)
            continue
        student = students.setdefault(m["uid"], _Student(m["uid"], name=m["name"], lms_late=False))
        student.lms_late = student.lms_late or bool(m["late"])
        student.files.append((m["file"], member))
        student.sources.append(member.name)
    return students, unmapped


def _map_moodle(members: list[_Member]) -> tuple[dict[str, _Student], list[_Member]]:
    students: dict[str, _Student] = {}
    unmapped: list[_Member] = []
    for member in members:
        head, _, tail = member.name.partition("/")
        m = _MOODLE.match(head)
        if not m or (tail and m["rest"]) or (not tail and not m["rest"]):
            unmapped.append(member)
            continue
        if m["plugin"] != "file":
            continue  # online text, comments: no code
        student = students.setdefault(m["pid"], _Student(m["pid"], name=m["name"]))
        student.files.append((tail or m["rest"], member))
        source = f"{head}/" if tail else member.name
        if source not in student.sources:
            student.sources.append(source)
    return students, unmapped


def _map_blackboard(members: list[_Member], tz: tzinfo | None) -> tuple[dict[str, _Student], list[_Member]]:
    attempts: dict[str, dict[str, list[tuple[re.Match, _Member]]]] = defaultdict(lambda: defaultdict(list))
    unmapped: list[_Member] = []
    for member in members:
        m = _BLACKBOARD.match(member.name)
        if not m:
            unmapped.append(member)
        else:
            attempts[m["user"]][m["stamp"]].append((m, member))
    students: dict[str, _Student] = {}
    for user, by_stamp in attempts.items():
        stamp = max(by_stamp)  # YYYY-MM-DD-HH-MM-SS sorts as time: the latest attempt is kept
        student = students[user] = _Student(user, submitted_at=_blackboard_time(stamp, tz))
        for m, member in sorted(by_stamp[stamp], key=lambda pair: pair[1].name):
            student.sources.append(member.name)
            if m["receipt"]:
                student.name = _receipt_name(member, user) or student.name
            else:
                student.files.append((m["file"], member))
    return students, unmapped


def _blackboard_time(stamp: str, tz: tzinfo | None) -> str:
    """The attempt stamp ``YYYY-MM-DD-HH-MM-SS`` as ISO 8601 with an offset.

    Blackboard writes the stamp in the Learn server's time zone and says not which. The caller passes it
    (``tz``); without one, this machine's local time zone is assumed (with the daylight-saving offset of that
    date), because the instructor downloading and grading usually sits in the institution's time zone, where
    its Learn server is configured. A grading server in UTC should pass the institution's zone.
    """
    naive = datetime.strptime(stamp, "%Y-%m-%d-%H-%M-%S")
    aware = naive.replace(tzinfo=tz) if tz is not None else naive.astimezone()
    return aware.isoformat()


def _receipt_name(member: _Member, user: str) -> str | None:
    """The ``Name: First Last (username)`` of a Blackboard receipt (at most 64 KiB read), or None."""
    if member.problem or member.open is None:
        return None
    try:
        with member.open() as fh:
            text = fh.read(64 * 1024).decode("utf-8", errors="replace")
    except (OSError, zipfile.BadZipFile, RuntimeError, ValueError):
        return None
    for m in _RECEIPT_NAME.finditer(text):
        if m["user"].strip() == user:
            return m["name"] or None
    return None


def _guess_format(members: list[_Member], tz: tzinfo | None) -> str | None:
    """The LMS whose naming maps the most members (None when none maps any)."""
    counts = {"canvas": len(members) - len(_map_canvas(members)[1]),
              "moodle": len(members) - len(_map_moodle(members)[1]),
              "blackboard": len(members) - len(_map_blackboard(members, tz)[1])}
    best = max(counts, key=lambda k: counts[k])
    return best if counts[best] else None


def _intake_lms(source: Path, fmt: str, staging: Path, tz: tzinfo | None) -> dict[str, IntakeRecord]:
    records: dict[str, IntakeRecord] = {}
    zf: zipfile.ZipFile | None = None
    try:
        if source.is_dir():
            members = list(_folder_members(source))
        else:
            try:
                zf = zipfile.ZipFile(source)
            except (zipfile.BadZipFile, OSError) as exc:
                raise CourseError(f"{source} is not a readable .zip ({type(exc).__name__}: {exc})",
                                  f"give the zip {_LMS_NAMES[fmt]} downloads, or the folder it unpacks to") from exc
            members = list(_zip_members(zf))
        mapper = {"canvas": _map_canvas, "moodle": _map_moodle,
                  "blackboard": lambda ms: _map_blackboard(ms, tz)}[fmt]
        students, unmapped = mapper(members)
        if members and not students:
            other = _guess_format(members, tz)
            hint = (f"it looks like a {_LMS_NAMES[other]} download: use --from {other}" if other and other != fmt
                    else f"give the zip of {_LMS_NAMES[fmt]}'s download of all submissions, as downloaded")
            raise CourseError(f"{source.name} is not a {_LMS_NAMES[fmt]} download: no member is named "
                              f"{_NAMING[fmt]}", hint)
        _stage_students(students, staging, records)
        for member in unmapped:
            rec = _unmapped(member, fmt)
            while rec.student in records:
                rec.student = student_id(rec.student + "_")
            records[rec.student] = rec
    finally:
        if zf is not None:
            zf.close()
    return records


# --- git clones --------------------------------------------------------------------------------------------------

def _git(clone: Path, *args: str, stdout: int | IO[bytes] = subprocess.PIPE) -> subprocess.CompletedProcess:
    """``git ARGS`` reading ``clone``: never its hooks or fsmonitor, no optional locks, safe.directory for it."""
    cmd = ["git", "-c", "core.hooksPath=/dev/null", "-c", "core.fsmonitor=false",
           "-c", f"safe.directory={clone}", "-C", str(clone), *args]
    return subprocess.run(cmd, stdout=stdout, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, env=_git_env(),
                          timeout=GIT_TIMEOUT, check=False)


def _filter_overrides(clone: Path) -> list[str]:
    """``-c`` options emptying every filter driver the clone's configuration names (``git archive`` would run
    a ``smudge`` command the clone's ``.git/config`` sets)."""
    proc = _git(clone, "config", "--includes", "--name-only", "--get-regexp", r"^filter\.")
    names = {line.rsplit(".", 1)[0] for line in proc.stdout.decode(errors="replace").splitlines() if line}
    out: list[str] = []
    for name in sorted(names):
        for key in ("smudge", "clean", "process"):
            out += ["-c", f"{name}.{key}="]
    return out


def _git_one(clone: Path, sid: str, staging: Path, before: datetime | None) -> IntakeRecord:
    """Stage the clone ``clone`` as ``staging/submissions/<sid>``: the last commit before ``before`` (else HEAD).

    Raises:
        NotGradable: not a git clone, no commit (before the deadline), export too big or unsafe.
    """
    record = IntakeRecord(student=sid, source=str(clone))
    if not (clone / ".git").exists() and not (clone / "HEAD").is_file():
        raise NotGradable("not a git clone (no .git)")
    if before is not None:
        when = before.astimezone(timezone.utc).strftime("%Y-%m-%d %H:%M:%S +0000")
        proc = _git(clone, "rev-list", "-1", f"--before={when}", "HEAD", "--")
    else:
        proc = _git(clone, "rev-parse", "--verify", "-q", "HEAD^{commit}")
    commit = proc.stdout.decode(errors="replace").strip()
    if proc.returncode != 0 or not re.fullmatch(r"[0-9a-f]{40,64}", commit):
        if proc.returncode == 0 or before is None:
            raise NotGradable(f"no commit before the deadline {before.isoformat()}" if before is not None
                              else "the clone has no commit")
        raise NotGradable(f"git cannot read the clone: {proc.stderr.decode(errors='replace').strip()[:200]}")
    shown = _git(clone, "show", "-s", "--format=%cI", commit)
    record.commit = commit
    record.submitted_at = datetime.fromisoformat(shown.stdout.decode().strip()).isoformat()
    tar = staging / ".intake-scratch" / f"{sid}.tar"
    tar.parent.mkdir(exist_ok=True)
    try:
        with open(tar, "wb") as out:
            _git_export(clone, _filter_overrides(clone), commit, out)
        (staging / ENTRIES / sid).mkdir(parents=True)
        extract_tar(tar, staging / ENTRIES / sid)
    finally:
        tar.unlink(missing_ok=True)
    return record


def _git_export(clone: Path, extra: list[str], commit: str, out: IO[bytes]) -> None:
    """``git archive --format=tar COMMIT`` of ``clone`` into ``out``, stopped past ``MAX_UNPACKED_BYTES`` (+ headers).

    Raises:
        NotGradable: git fails, takes longer than :data:`GIT_TIMEOUT`, or the export is too big.
    """
    cmd = ["git", "-c", "core.hooksPath=/dev/null", "-c", "core.fsmonitor=false", "-c", f"safe.directory={clone}",
           *extra, "-C", str(clone), "archive", "--format=tar", commit]
    limit = MAX_UNPACKED_BYTES + (1 << 20)
    too_big = False
    with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
                          env=_git_env()) as proc:
        assert proc.stdout is not None
        written = 0
        while chunk := proc.stdout.read(1 << 20):
            written += len(chunk)
            if written > limit:
                too_big = True
                proc.kill()
                break
            out.write(chunk)
        try:
            _, err = proc.communicate(timeout=GIT_TIMEOUT)
        except subprocess.TimeoutExpired:
            proc.kill()
            raise NotGradable(f"git archive took more than {GIT_TIMEOUT:g} s") from None
    if too_big:
        raise NotGradable(f"the commit holds more than {MAX_UNPACKED_BYTES} bytes")
    if proc.returncode != 0:
        raise NotGradable(f"git archive failed: {err.decode(errors='replace').strip()[:200]}")


def _git_env() -> dict[str, str]:
    """git's environment: no optional locks (nothing written into the clone), no prompt, no system config."""
    return {**os.environ, "GIT_OPTIONAL_LOCKS": "0", "GIT_TERMINAL_PROMPT": "0", "GIT_CONFIG_NOSYSTEM": "1"}


def _intake_git(source: Path, staging: Path, before: datetime | None) -> dict[str, IntakeRecord]:
    if not source.is_dir():
        raise CourseError(f"{source} is not a folder", "with --from git, give a folder of git clones, one per student")
    records: dict[str, IntakeRecord] = {}
    try:
        for entry in discover(source):
            sid = entry.student
            if entry.problem:
                records[sid] = IntakeRecord(student=sid, source=str(entry.path), problem=entry.problem)
                continue
            clone = entry.path
            try:
                if clone.is_symlink() or not clone.is_dir():
                    raise NotGradable("not a git clone (a folder is expected)")
                records[sid] = _git_one(clone, sid, staging, before)
            except NotGradable as exc:
                shutil.rmtree(staging / ENTRIES / sid, ignore_errors=True)
                records[sid] = IntakeRecord(student=sid, source=str(clone), problem=exc.message)
            except (OSError, subprocess.SubprocessError, ValueError) as exc:
                shutil.rmtree(staging / ENTRIES / sid, ignore_errors=True)
                records[sid] = IntakeRecord(student=sid, source=str(clone),
                                            problem=f"cannot read the clone: {type(exc).__name__}: {exc}")
    finally:
        shutil.rmtree(staging / ".intake-scratch", ignore_errors=True)
    return records


# --- the entry points --------------------------------------------------------------------------------------------

def _prepare_staging(source: Path, staging: Path) -> None:
    """Refuse a staging folder inside ``source`` (or holding it) or holding something else; empty an old intake.

    Raises:
        CourseError: ``staging`` overlaps ``source``, or is a non-empty folder without ``intake.json``.
    """
    src, stg = source.resolve(), staging.resolve()
    if stg.is_relative_to(src) or src.is_relative_to(stg):  # never written into, never emptied with an old intake
        raise CourseError(f"the intake folder {staging} overlaps {source}", "choose an --out folder elsewhere")
    if staging.is_symlink() or (staging.exists() and not staging.is_dir()):
        raise CourseError(f"{staging} is not a folder", "choose another --out folder")
    if staging.is_dir() and any(staging.iterdir()):
        if not (staging / MANIFEST).is_file():
            raise CourseError(f"{staging} is not empty and holds no {MANIFEST} of an earlier intake",
                              "choose another --out folder")
        shutil.rmtree(staging)  # an earlier intake of ours: taken again from the source
    staging.mkdir(parents=True, exist_ok=True)


def intake(source: Path, fmt: str, staging: Path, *, before: datetime | None = None,
           tz: tzinfo | None = None) -> IntakeReport:
    """Turn an LMS download or a folder of git clones into ``staging/submissions/`` plus ``staging/intake.json``.

    Args:
        source: ``canvas`` / ``moodle`` / ``blackboard``: the LMS's zip of all submissions (or the folder it
            unpacks to); ``git``: a folder of git clones, one per student (folder name = student id);
            ``folder``: today's submissions folder (one entry per student, see :mod:`ros2course.batch.archive`).
            Only read, never written.
        fmt: one of :data:`FORMATS`.
        staging: the folder written: ``submissions/`` with one entry per student, named by the safe student id
            (today's submissions folder, what ``grade`` grades), and ``intake.json`` (see :class:`IntakeRecord`). Created; an earlier intake there is replaced. For ``folder`` only
            ``intake.json`` is written (the entries are graded where they are).
        before: timezone-aware deadline; ``git`` takes each clone at its last commit before it (committer
            date, ``git rev-list -1 --before``), else HEAD. Ignored by the other formats (late policies read
            ``submitted_at``).
        tz: the time zone of Blackboard's attempt stamps (default: this machine's, see :func:`_blackboard_time`).

    Returns:
        The :class:`IntakeReport`; ``report.folder`` is the folder to grade.

    Raises:
        CourseError: unknown ``fmt``, a naive ``before``, ``source`` missing or unreadable, a download of which
            no member follows ``fmt``'s naming (the hint names the format it looks like), ``staging`` overlapping
            ``source`` or holding something else. A bad student or member never raises: its record says why.
    """
    if fmt not in FORMATS:
        raise CourseError(f"unknown intake format {fmt!r}", f"use one of {', '.join(FORMATS)}")
    if before is not None and (before.tzinfo is None or before.utcoffset() is None):
        raise CourseError(f"the deadline {before.isoformat()} has no time zone", "e.g. 2026-03-01T23:59:00+01:00")
    if not source.exists():
        raise CourseError(f"{source} does not exist", "give the LMS download or the folder of submissions")
    source, staging = source.absolute(), staging.absolute()
    _prepare_staging(source, staging)
    if fmt != "folder":
        (staging / ENTRIES).mkdir()
    if fmt == "folder":
        if not source.is_dir():
            raise CourseError(f"{source} is not a folder", "give the folder that holds one entry per student")
        records = {s.student: IntakeRecord(student=s.student, source=str(s.path), problem=s.problem or None)
                   for s in discover(source)}
        folder = source
    elif fmt == "git":
        records = _intake_git(source, staging, before)
        folder = staging / ENTRIES
    else:
        records = _intake_lms(source, fmt, staging, tz)
        folder = staging / ENTRIES
    records = dict(sorted(records.items()))
    payload = {"format": fmt, "source": str(source), "before": before.isoformat() if before else None,
               "students": [rec.model_dump() for rec in records.values()]}
    atomic_write_text(staging / MANIFEST, json.dumps(payload, indent=2) + "\n")
    return IntakeReport(fmt, source, staging, folder, records)


def load_intake(staging: Path) -> dict[str, IntakeRecord]:
    """The records of ``staging/intake.json`` (written by :func:`intake`), student id -> record.

    Args:
        staging: the intake folder (``OUTDIR/intake`` of ``ros2course grade --from ...``).

    Raises:
        CourseError: no ``intake.json`` there, or it cannot be read as a manifest.
    """
    path = staging / MANIFEST
    try:
        payload = json.loads(path.read_text(encoding="utf-8"))
        return {rec.student: rec for rec in (IntakeRecord.model_validate(item) for item in payload["students"])}
    except FileNotFoundError as exc:
        raise CourseError(f"no {MANIFEST} in {staging}", "run `ros2course grade --from ...` first") from exc
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise CourseError(f"{path} cannot be read: {type(exc).__name__}: {exc}",
                          "run the intake again (ros2course grade --from ...)") from exc


def parse_deadline(text: str) -> datetime:
    """``--before``'s ISO 8601 date and time, which must carry a time zone (``Z`` or ``+HH:MM``).

    Raises:
        CourseError: not ISO 8601, or no time zone (one line, with a hint).
    """
    try:
        when = datetime.fromisoformat(text.strip().replace("Z", "+00:00").replace("z", "+00:00"))
    except ValueError as exc:
        raise CourseError(f"--before {text!r} is not an ISO 8601 date and time",
                          "e.g. --before 2026-03-01T23:59:00+01:00") from exc
    if when.tzinfo is None or when.utcoffset() is None:
        raise CourseError(f"--before {text!r} has no time zone",
                          "add the offset of the deadline's time zone, e.g. --before 2026-03-01T23:59:00+01:00")
    return when
