"""What graded each row of a batch, and regrading exactly what changed since (issue 39).

Every record ``ros2course grade`` appends to ``results.jsonl`` carries a ``graded_with`` object:

* ``grader``: the lesson's grader fingerprint (:func:`ros2course.grade.fingerprint.grader_fingerprint`:
  the grader and the course modules it imports, the kit and grading-engine modules they run on,
  ``lesson.yaml``, the reference files), 16 hex digits;
* ``submission``: the submission's content digest (:func:`submission_digest`), 16 hex digits;
* ``at``: when it was graded (ISO 8601, UTC);
* ``regrade_failed`` (only on a kept row): why a regrade did not replace it.

``grade --regrade changed`` regrades exactly the rows whose grader or submission changed since they
were graded (a row recorded before provenance was kept counts as changed: nothing says what graded
it); ``--regrade all`` every row; ``--only STUDENT`` (an appeal) that student's rows, with the same
isolation. A regrade never loses a row: one the grading machine failed on (a grader error, a
timeout) keeps the previous result, appended again with ``regrade_failed`` saying why
(PrairieLearn #14914 and #786 ask for this: re-run the external grader on existing submissions after
the grader code is updated, and only those it concerns).

What each regrade changed goes to ``OUTDIR/regrades.jsonl`` (:class:`RegradeChange`, one line per
regraded row: old and new score, the checks whose points moved, old and new grader and
submission), and ``OUTDIR/run.json`` remembers the submissions folder and the lessons of the batch
(``ros2course report OUTDIR`` finds the submissions there for its similarity section).
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import hashlib
import json
import os
import stat
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from ros2course.batch.archive import Submission
from ros2course.files import atomic_write_text
from ros2course.grade.results import LessonResult, Status

#: The key of a ``results.jsonl`` record that says what graded it.
GRADED_WITH = "graded_with"
#: ``--regrade`` values: the rows whose grader or submission changed, or every row.
REGRADE_MODES = ("changed", "all")
#: Folders a batch never copies from a submission (:data:`ros2course.batch.archive._SKIP_DIRS`), so
#: never part of what is graded: a change there changes no verdict.
_NOT_GRADED_DIRS = frozenset({"__pycache__", ".git"})
_CHUNK = 1 << 20


def _hash_file(path: Path, digest: Any) -> None:
    with open(path, "rb") as handle:
        while chunk := handle.read(_CHUNK):
            digest.update(chunk)


def submission_digest(submission: Submission) -> str:
    """sha256 (hex, first 16 digits) of what a batch grades of ``submission``.

    An archive: its bytes. A folder: every path below it (sorted, relative, POSIX) with its kind
    and content: a file's bytes, a symbolic link's target (never followed), a folder's name; other
    kinds (devices, sockets) by kind only; ``.git`` and ``__pycache__`` left out, as the batch's
    copy leaves them out (:func:`ros2course.batch.archive.prepare`). Timestamps and permissions
    are not part of it: a verdict is about the files a learner has, whatever their times.
    A submission that cannot be read gives the digest of its problem (it is regraded when that
    changes).
    """
    digest = hashlib.sha256()
    path = submission.path
    try:
        if submission.problem:
            digest.update(f"problem\0{submission.problem}".encode())
        elif path.is_file():
            _hash_file(path, digest)
        else:
            for root, dirs, files in os.walk(path, followlinks=False):
                dirs[:] = sorted(d for d in dirs if d not in _NOT_GRADED_DIRS)
                base = Path(root)
                for name in [*dirs, *sorted(files)]:
                    item = base / name
                    rel = item.relative_to(path).as_posix()
                    mode = item.lstat().st_mode
                    if stat.S_ISLNK(mode):
                        digest.update(f"L\0{rel}\0{os.readlink(item)}\0".encode("utf-8", "surrogateescape"))
                    elif stat.S_ISDIR(mode):
                        digest.update(f"D\0{rel}\0".encode("utf-8", "surrogateescape"))
                    elif stat.S_ISREG(mode):
                        digest.update(f"F\0{rel}\0{item.lstat().st_size}\0".encode("utf-8", "surrogateescape"))
                        _hash_file(item, digest)
                    else:
                        digest.update(f"O\0{rel}\0{stat.S_IFMT(mode)}\0".encode("utf-8", "surrogateescape"))
    except OSError as exc:
        digest.update(f"unreadable\0{exc}".encode("utf-8", "surrogateescape"))
    return digest.hexdigest()[:16]


def graded_with(grader: str, submission: str, **more: str) -> dict[str, str]:
    """The ``graded_with`` object of a record graded now by grader fingerprint ``grader`` of a submission
    of digest ``submission`` (``more``: e.g. ``regrade_failed``)."""
    return {"grader": grader, "submission": submission,
            "at": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), **more}


def read_graded_with(path: Path) -> dict[tuple[str, str], dict[str, str]]:
    """``(student, lesson) -> graded_with`` of the last record of each pair in ``results.jsonl`` at ``path``
    ({} for a pair whose last record has none: graded before provenance was kept). Lines
    :func:`ros2course.report.gradebook.read_results` skips are skipped here too; a missing file has none."""
    out: dict[tuple[str, str], dict[str, str]] = {}
    try:
        handle = open(path, encoding="utf-8", errors="replace")
    except FileNotFoundError:
        return out
    with handle:
        for line in handle:
            try:
                record = json.loads(line)
            except ValueError:
                continue
            if not isinstance(record, dict) or "student" not in record or "lesson" not in record:
                continue
            found = record.get(GRADED_WITH)
            out[(str(record["student"]), str(record["lesson"]))] = (
                {str(k): str(v) for k, v in found.items()} if isinstance(found, dict) else {})
    return out


def why_regrade(before: Mapping[str, str] | None, grader: str, submission: str, mode: str | None,
                asked: bool) -> str:
    """Why a row is regraded now, or "" when it is not.

    Args:
        before: the row's ``graded_with`` ({} when it has none; None: no row yet, which is graded as new).
        grader: the lesson's grader fingerprint now.
        submission: the submission's digest now.
        mode: ``--regrade`` (``changed``, ``all``) or None (a plain or ``--resume`` run: never regrade).
        asked: the student was named by ``--only`` (an appeal: always regraded).
    """
    if before is None:
        return "new"
    if asked:
        return "asked (--only)"
    if mode == "all":
        return "asked (--regrade all)"
    if mode != "changed":
        return ""
    if not before:
        return "graded before grader fingerprints were recorded"
    reasons = []
    if before.get("grader") != grader:
        reasons.append(f"grader {before.get('grader', '?')} -> {grader}")
    if before.get("submission") != submission:
        reasons.append("submission changed")
    return ", ".join(reasons)


def failed_regrade(new: LessonResult) -> str:
    """Why ``new`` must not replace the row it regrades ("" when it may): the grading machine failed
    (a grader error) or the run timed out; a verdict about the submission (graded, or not gradable
    because it does not build) always replaces it."""
    if new.status is Status.GRADER_ERROR:
        return f"grader error: {new.message.splitlines()[0] if new.message else 'no message'}"
    if new.status is Status.NOT_GRADABLE and "timed out" in new.message:
        return new.message.splitlines()[0]
    return ""


@dataclasses.dataclass
class RegradeChange:
    """What one regrade did to one row (a line of ``OUTDIR/regrades.jsonl``).

    Attributes:
        student, lesson: the row.
        why: :func:`why_regrade`'s reason.
        old_score, new_score, max_score: points (new_score is the old one when the previous row was kept).
        checks: check id -> ``[old points, new points]`` for each check whose points changed (a check one
            side lacks has None there).
        old, new: the ``graded_with`` of the row before and of the new row.
        kept: why the previous row was kept (:func:`failed_regrade`), "" when the new one replaced it.
    """

    student: str
    lesson: str
    why: str
    old_score: float
    new_score: float
    max_score: float
    checks: dict[str, list[float | None]]
    old: dict[str, str]
    new: dict[str, str]
    kept: str = ""

    @property
    def direction(self) -> str:
        """``up``, ``down``, ``same`` or ``kept``."""
        if self.kept:
            return "kept"
        if self.new_score > self.old_score:
            return "up"
        return "down" if self.new_score < self.old_score else "same"

    def to_json(self) -> dict[str, Any]:
        """The ``regrades.jsonl`` object."""
        return {**dataclasses.asdict(self), "direction": self.direction}


def compare(old: LessonResult, new: LessonResult, why: str, old_with: Mapping[str, str],
            new_with: Mapping[str, str], kept: str = "") -> RegradeChange:
    """The :class:`RegradeChange` from ``old`` to ``new`` (both of one student and lesson)."""
    before = {c.id: c.points for c in old.checks}
    after = {c.id: c.points for c in new.checks} if not kept else before
    moved = {cid: [before.get(cid), after.get(cid)] for cid in [*before, *(c for c in after if c not in before)]
             if before.get(cid) != after.get(cid)}
    return RegradeChange(new.student, new.lesson, why, old.score, old.score if kept else new.score,
                         new.max_score or old.max_score, moved, dict(old_with), dict(new_with), kept)


def append_changes(out_dir: Path, changes: Iterable[RegradeChange]) -> None:
    """Append ``changes`` to ``OUTDIR/regrades.jsonl`` (one JSON object per line, flushed)."""
    lines = "".join(json.dumps(c.to_json(), separators=(",", ":"), ensure_ascii=False) + "\n" for c in changes)
    if lines:
        with open(out_dir / "regrades.jsonl", "a", encoding="utf-8") as handle:
            handle.write(lines)
            handle.flush()
            os.fsync(handle.fileno())


def write_run_file(out_dir: Path, submissions: Path, lessons: list[str]) -> Path:
    """Write ``OUTDIR/run.json``: the submissions folder (absolute) and the lessons of the batch (those of
    earlier runs into the same OUTDIR kept), so that ``report OUTDIR`` finds the submissions again."""
    path = out_dir / "run.json"
    try:
        before = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        before = {}
    known = [lesson for lesson in before.get("lessons", []) if isinstance(lesson, str)] if isinstance(before, dict) else []
    data = {"submissions": str(submissions.absolute()), "lessons": [*known, *(x for x in lessons if x not in known)],
            "updated": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")}
    atomic_write_text(path, json.dumps(data, indent=1) + "\n")
    return path
