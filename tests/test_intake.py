"""Intake of a class's submissions from an LMS download or from git clones (issue 39, :mod:`ros2course.batch.intake`).

Every download is built here, following each LMS's documented naming, with made-up students; no real student
data. Nothing here starts ROS or grades.
"""

from __future__ import annotations

import hashlib
import io
import os
import stat
import subprocess
import tarfile
import zipfile
from datetime import datetime, timedelta, timezone
from pathlib import Path

import pytest
from ros2course.batch import archive
from ros2course.batch import intake as intake_mod
from ros2course.batch.intake import intake, load_intake, parse_deadline
from ros2course.errors import CourseError

PACKAGE_XML = "<package format='3'><name>pkg</name><version>0.0.1</version></package>\n"
WORKSPACE = {"ws/src/pkg/package.xml": PACKAGE_XML, "ws/src/pkg/setup.py": "print('hi')\n",
             "ws/src/pkg/pkg/node.py": "x = 1\n"}


# --- helpers -------------------------------------------------------------------------------------------------------

def zip_bytes(files: dict[str, str | bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in files.items():
            zf.writestr(name, data)
    return buf.getvalue()


def tar_bytes(files: dict[str, str | bytes], extra: list[tarfile.TarInfo] = ()) -> bytes:
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w:gz") as tf:
        for name, data in files.items():
            raw = data.encode() if isinstance(data, str) else data
            info = tarfile.TarInfo(name)
            info.size = len(raw)
            tf.addfile(info, io.BytesIO(raw))
        for info in extra:
            tf.addfile(info)
    return buf.getvalue()


def write_zip(path: Path, members: dict[str, str | bytes | tuple[zipfile.ZipInfo, bytes]]) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in members.items():
            if isinstance(data, tuple):
                zf.writestr(*data)
            else:
                zf.writestr(name, data)
    return path


def snapshot(root: Path, skip: Path | None = None) -> dict[str, str]:
    """Every path below ``root`` (but ``skip``) -> its kind and content hash: what changed outside staging."""
    out: dict[str, str] = {}
    for path in sorted(root.rglob("*")):
        if skip is not None and (path == skip or skip in path.parents):
            continue
        st = path.lstat()
        if stat.S_ISREG(st.st_mode):
            out[str(path)] = hashlib.sha256(path.read_bytes()).hexdigest()
        else:
            out[str(path)] = f"mode {stat.S_IFMT(st.st_mode):o}"
    return out


def canvas_zip(path: Path, extra: dict | None = None) -> Path:
    """A Canvas "Download Submissions" zip: a workspace zip, a LATE tar.gz, a student with two loose files."""
    return write_zip(path, {
        "smithbob_101_9001_workspace.zip": zip_bytes(WORKSPACE),
        "doejane_LATE_102_9002_ws.tar.gz": tar_bytes(WORKSPACE),
        "leeann_103_9003_package.xml": PACKAGE_XML,
        "leeann_103_9003_setup.py": "print('setup')\n",
        **(extra or {}),
    })


# --- Canvas --------------------------------------------------------------------------------------------------------

def test_canvas_download_is_staged_one_folder_per_user_id(tmp_path):
    src = canvas_zip(tmp_path / "submissions.zip")
    before = snapshot(tmp_path)
    report = intake(src, "canvas", tmp_path / "out" / "intake")
    staging = tmp_path / "out" / "intake" / "submissions"
    assert report.folder == staging and sorted(report.taken) == ["101", "102", "103"] and not report.problems
    assert (staging / "101" / "ws" / "src" / "pkg" / "package.xml").read_text() == PACKAGE_XML
    assert (staging / "102" / "ws" / "src" / "pkg" / "pkg" / "node.py").is_file()
    assert sorted(p.name for p in (staging / "103").iterdir()) == ["package.xml", "setup.py"]
    records = load_intake(staging.parent)
    assert records["101"].name == "smithbob" and records["101"].lms_late is False
    assert records["102"].lms_late is True and records["102"].source == "doejane_LATE_102_9002_ws.tar.gz"
    assert records["103"].source == "leeann_103_9003_package.xml; leeann_103_9003_setup.py"
    assert all(r.submitted_at is None and r.commit is None for r in records.values())
    # exactly today's submissions folder: archive.discover + prepare read it
    entries = archive.discover(staging)
    assert [e.student for e in entries] == ["101", "102", "103"] and not any(e.problem for e in entries)
    ws = archive.prepare(entries[2], tmp_path / "out" / "scratch")
    assert (ws / "src" / "103" / "package.xml").is_file()
    assert snapshot(tmp_path, skip=tmp_path / "out") == before  # the download untouched, nothing written beside


def test_canvas_unpacked_download_folder_and_multiple_numbered_files(tmp_path):
    src = tmp_path / "unpacked"
    src.mkdir()
    (src / "smithbob_101_9001_notes.txt").write_text("a")
    (src / "smithbob_101_9001_notes-1.txt").write_text("b")  # Canvas's -N suffix: both kept
    report = intake(src, "canvas", tmp_path / "staging")
    assert sorted(p.name for p in (report.folder / "101").iterdir()) == ["notes-1.txt", "notes.txt"]
    assert report.taken == ["101"]


def test_intake_again_replaces_an_earlier_intake_but_never_a_foreign_folder(tmp_path):
    src = canvas_zip(tmp_path / "s.zip")
    intake(src, "canvas", tmp_path / "staging")
    intake(src, "canvas", tmp_path / "staging")
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "keep.txt").write_text("x")
    with pytest.raises(CourseError, match="not empty"):
        intake(src, "canvas", tmp_path / "other")
    assert (tmp_path / "other" / "keep.txt").read_text() == "x"


# --- Moodle --------------------------------------------------------------------------------------------------------

def test_moodle_folders_form(tmp_path):
    src = write_zip(tmp_path / "moodle.zip", {
        "Ann Lee_5501_assignsubmission_file_/ws.zip": zip_bytes(WORKSPACE),
        "Bo Chen_5502_assignsubmission_file_/src/pkg/package.xml": PACKAGE_XML,
        "Bo Chen_5502_assignsubmission_file_/src/pkg/setup.py": "x\n",
        "Bo Chen_5502_assignsubmission_onlinetext_/onlinetext.html": "<p>hello</p>",
    })
    report = intake(src, "moodle", tmp_path / "staging")
    assert report.taken == ["5501", "5502"] and not report.problems
    staging = report.folder
    assert (staging / "5501" / "ws" / "src" / "pkg" / "setup.py").is_file()
    assert (staging / "5502" / "src" / "pkg" / "package.xml").is_file()
    assert not (staging / "5502" / "onlinetext.html").exists()
    rec = load_intake(tmp_path / "staging")["5502"]
    assert rec.name == "Bo Chen" and rec.lms_late is None and rec.source == "Bo Chen_5502_assignsubmission_file_/"


def test_moodle_flat_form(tmp_path):
    src = write_zip(tmp_path / "moodle.zip", {
        "Ann Lee_5501_assignsubmission_file_workspace.tar.gz": tar_bytes(WORKSPACE),
        "Bo Chen_5502_assignsubmission_file_package.xml": PACKAGE_XML,
    })
    report = intake(src, "moodle", tmp_path / "staging")
    assert report.taken == ["5501", "5502"]
    assert (report.folder / "5501" / "ws" / "src" / "pkg" / "package.xml").is_file()
    assert (report.folder / "5502" / "package.xml").is_file()
    assert load_intake(tmp_path / "staging")["5501"].name == "Ann Lee"


# --- Blackboard ----------------------------------------------------------------------------------------------------

def receipt(name: str, user: str, when: str) -> str:
    return (f"Name: {name} ({user})\nAssignment: Lab 1\nDate Submitted: {when}\nCurrent Grade: Needs Grading\n\n"
            "Submission Field:\nThere is no student submission text data for this assignment.\n")


def test_blackboard_keeps_the_latest_attempt(tmp_path):
    src = write_zip(tmp_path / "gradebook.zip", {
        "Lab 1_jdoe_attempt_2026-02-01-10-00-00.txt": receipt("Jane Doe", "jdoe", "Sunday, 1 February 2026 10:00:00"),
        "Lab 1_jdoe_attempt_2026-02-01-10-00-00_old.zip": zip_bytes({"old/src/pkg/package.xml": PACKAGE_XML}),
        "Lab 1_jdoe_attempt_2026-02-03-18-30-05.txt": receipt("Jane Doe", "jdoe", "Tuesday, 3 February 2026 18:30:05"),
        "Lab 1_jdoe_attempt_2026-02-03-18-30-05_ws.zip": zip_bytes(WORKSPACE),
        "Lab 1_bsmith_attempt_2026-02-02-09-15-00.txt": receipt("Bob Smith", "bsmith", "Monday, 2 February 2026"),
        "Lab 1_bsmith_attempt_2026-02-02-09-15-00_package.xml": PACKAGE_XML,
    })
    tz = timezone(timedelta(hours=-5))
    report = intake(src, "blackboard", tmp_path / "staging", tz=tz)
    staging = report.folder
    assert report.taken == ["bsmith", "jdoe"]
    assert (staging / "jdoe" / "ws" / "src" / "pkg" / "package.xml").is_file()
    assert not (staging / "jdoe" / "old").exists()
    rec = load_intake(tmp_path / "staging")["jdoe"]
    assert rec.name == "Jane Doe" and rec.submitted_at == "2026-02-03T18:30:05-05:00"
    assert datetime.fromisoformat(rec.submitted_at) == datetime(2026, 2, 3, 23, 30, 5, tzinfo=timezone.utc)
    assert "2026-02-03-18-30-05_ws.zip" in rec.source and "2026-02-01" not in rec.source


def test_blackboard_without_a_time_zone_assumes_this_machines(tmp_path):
    src = write_zip(tmp_path / "g.zip", {"A_u1_attempt_2026-07-01-12-00-00_package.xml": PACKAGE_XML})
    rec = intake(src, "blackboard", tmp_path / "staging").records["u1"]
    assert datetime.fromisoformat(rec.submitted_at) == datetime(2026, 7, 1, 12).astimezone()


def test_blackboard_attempt_with_only_a_receipt_is_not_taken(tmp_path):
    src = write_zip(tmp_path / "g.zip", {"A_u1_attempt_2026-07-01-12-00-00.txt": receipt("U One", "u1", "x"),
                                         "A_u2_attempt_2026-07-01-12-00-00_package.xml": PACKAGE_XML})
    report = intake(src, "blackboard", tmp_path / "staging", tz=timezone.utc)
    assert report.problems == {"u1": "no file submitted"} and report.taken == ["u2"]


# --- git -----------------------------------------------------------------------------------------------------------

def git(repo: Path, *args: str, when: str | None = None) -> str:
    env = {**os.environ, "GIT_AUTHOR_NAME": "S", "GIT_AUTHOR_EMAIL": "s@example.org", "GIT_COMMITTER_NAME": "S",
           "GIT_COMMITTER_EMAIL": "s@example.org", "GIT_CONFIG_NOSYSTEM": "1", "HOME": str(repo.parent)}
    if when:
        env["GIT_AUTHOR_DATE"] = env["GIT_COMMITTER_DATE"] = when
    return subprocess.run(["git", "-C", str(repo), *args], env=env, check=True, capture_output=True,
                          text=True).stdout.strip()


def commit(repo: Path, files: dict[str, str], when: str) -> str:
    for name, text in files.items():
        (repo / name).parent.mkdir(parents=True, exist_ok=True)
        (repo / name).write_text(text)
    git(repo, "add", "-A")
    git(repo, "commit", "-q", "-m", f"at {when}", when=when)
    return git(repo, "rev-parse", "HEAD")


@pytest.fixture
def clones(tmp_path) -> Path:
    root = tmp_path / "clones"
    for student in ("alice", "bob", "carol"):
        (root / student).mkdir(parents=True)
        git(root / student, "init", "-q", "-b", "main")
    commit(root / "alice", {"src/pkg/package.xml": PACKAGE_XML, "src/pkg/v.txt": "1"}, "2026-01-10T12:00:00+00:00")
    commit(root / "alice", {"src/pkg/v.txt": "2"}, "2026-01-20T12:00:00+00:00")
    commit(root / "bob", {"src/pkg/package.xml": PACKAGE_XML}, "2026-01-20T12:00:00+00:00")
    # carol's clone carries a filter driver (a command git archive would run) and a hook: neither may run
    commit(root / "carol", {"src/pkg/package.xml": PACKAGE_XML, ".gitattributes": "* filter=evil\n"},
           "2026-01-12T08:00:00+01:00")
    marker = tmp_path / "pwned"
    git(root / "carol", "config", "filter.evil.smudge", f"touch {marker}; cat")
    hook = root / "carol" / ".git" / "hooks" / "post-checkout"
    hook.write_text(f"#!/bin/sh\ntouch {marker}\n")
    hook.chmod(0o755)
    (root / "notes.txt").write_text("not a clone")
    return root


def test_git_before_takes_the_last_commit_before_the_deadline(tmp_path, clones):
    first = git(clones / "alice", "rev-list", "--max-parents=0", "HEAD")
    before_tree = snapshot(clones)
    deadline = datetime(2026, 1, 15, 13, 0, tzinfo=timezone(timedelta(hours=1)))
    report = intake(clones, "git", tmp_path / "out" / "intake", before=deadline)
    staging = report.folder
    records = load_intake(tmp_path / "out" / "intake")
    assert records["alice"].commit == first and records["alice"].submitted_at == "2026-01-10T12:00:00+00:00"
    assert (staging / "alice" / "src" / "pkg" / "v.txt").read_text() == "1"
    assert records["bob"].problem.startswith("no commit before the deadline 2026-01-15T13:00:00+01:00")
    assert not (staging / "bob").exists()
    assert records["carol"].submitted_at == "2026-01-12T08:00:00+01:00"
    assert (staging / "carol" / "src" / "pkg" / "package.xml").read_text() == PACKAGE_XML
    assert "not a folder" in records["notes.txt"].problem
    assert sorted(report.taken) == ["alice", "carol"]
    assert not (tmp_path / "pwned").exists(), "a filter driver or hook of the clone ran"
    assert snapshot(clones) == before_tree, "the clones were written to"


def test_git_without_before_takes_head(tmp_path, clones):
    report = intake(clones, "git", tmp_path / "staging")
    assert (report.folder / "alice" / "src" / "pkg" / "v.txt").read_text() == "2"
    assert report.records["bob"].commit == git(clones / "bob", "rev-parse", "HEAD")
    assert sorted(report.taken) == ["alice", "bob", "carol"]


def test_git_empty_clone_and_plain_folder(tmp_path):
    root = tmp_path / "clones"
    (root / "empty").mkdir(parents=True)
    git(root / "empty", "init", "-q")
    (root / "plain").mkdir()
    report = intake(root, "git", tmp_path / "staging")
    assert report.problems == {"empty": "the clone has no commit", "plain": "not a git clone (no .git)"}


# --- hostile downloads ---------------------------------------------------------------------------------------------

def test_hostile_canvas_members_make_only_their_records_not_gradable(tmp_path, monkeypatch):
    cap = 1 << 20
    monkeypatch.setattr(archive, "MAX_UNPACKED_BYTES", cap)  # the caps, made small for a fast zip bomb
    monkeypatch.setattr(intake_mod, "MAX_UNPACKED_BYTES", cap)
    link = zipfile.ZipInfo("mallory_105_9005_link")
    link.external_attr = (stat.S_IFLNK | 0o777) << 16
    device = tarfile.TarInfo("ws/src/dev")
    device.type = tarfile.CHRTYPE
    src = canvas_zip(tmp_path / "submissions.zip", {
        "../escape.txt": "x",
        "eve_104_9004_../../escape.txt": "x",
        "/abs_106_9006_x.txt": "x",
        "mallory_105_9005_link": (link, b"/etc/passwd"),
        "bomb_107_9007_ws.zip": zip_bytes({"ws/src/zeros.bin": b"\0" * (2 * cap)}),
        "dev_108_9008_ws.tar.gz": tar_bytes({"ws/src/pkg/package.xml": PACKAGE_XML}, [device]),
        "linky_109_9009_ws.tar.gz": tar_bytes({}, [_symlink("ws/src/out", "../../../../etc")]),
        "big_110_9010_blob.bin": b"\0" * (2 * cap),
        "README.txt": "instructions",
        "__MACOSX/._smithbob_101_9001_workspace.zip": "resource fork",
    })
    before = snapshot(tmp_path)
    report = intake(src, "canvas", tmp_path / "out" / "intake")
    staging = tmp_path / "out" / "intake"
    assert sorted(report.taken) == ["101", "102", "103"]  # the rest of the class is taken
    problems = report.problems
    assert "symbolic link" in problems["105"]
    assert "more than" in problems["107"] and not (report.folder / "107").exists()
    assert "device or fifo" in problems["108"] and not (report.folder / "108").exists()
    assert "points outside" in problems["109"]
    assert "more than" in problems["110"]
    assert "does not follow Canvas's naming" in problems["unmapped_README.txt"]
    assert not any("MACOSX" in sid for sid in report.records)
    unmapped = {sid: why for sid, why in problems.items() if sid.startswith("unmapped_")}
    assert sum("escaping" in why for why in unmapped.values()) == 2 and any("absolute" in w for w in unmapped.values())
    assert load_intake(staging).keys() == report.records.keys()
    assert {p.name for p in staging.iterdir()} == {"submissions", "intake.json"}
    assert {p.name for p in report.folder.iterdir()} == {"101", "102", "103"}
    assert snapshot(tmp_path, skip=tmp_path / "out") == before  # nothing written outside staging
    assert not (tmp_path / "escape.txt").exists() and not (tmp_path / "out" / "escape.txt").exists()


def _symlink(name: str, target: str) -> tarfile.TarInfo:
    info = tarfile.TarInfo(name)
    info.type = tarfile.SYMTYPE
    info.linkname = target
    return info


def test_hostile_unpacked_download_fifo_and_symlink(tmp_path):
    src = tmp_path / "unpacked"
    src.mkdir()
    (src / "smithbob_101_9001_package.xml").write_text(PACKAGE_XML)
    os.mkfifo(src / "fifo_102_9002_pipe")
    (src / "linky_103_9003_passwd").symlink_to("/etc/passwd")
    (src / "dirlink_104_9004_d").symlink_to(tmp_path)
    report = intake(src, "canvas", tmp_path / "staging")
    assert report.taken == ["101"]
    assert "fifo" in report.problems["102"]
    assert "symbolic link" in report.problems["103"] and "symbolic link" in report.problems["104"]


def test_zip_member_lying_about_its_size_is_refused(tmp_path):
    path = write_zip(tmp_path / "s.zip", {"liar_101_9001_a.txt": b"A" * 5000, "ok_102_9002_b.txt": b"b"})
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as zf:
        info = zf.getinfo("liar_101_9001_a.txt")
    # declare 10 bytes in the central directory (what zipfile reads): a bomb lying about its size
    central = data.rfind(b"PK\x01\x02", 0, data.rfind(b"liar_101"))
    data[central + 24:central + 28] = (10).to_bytes(4, "little")
    path.write_bytes(bytes(data))
    report = intake(path, "canvas", tmp_path / "staging")
    assert info.file_size == 5000
    # zipfile stops at the declared size, then the CRC check fails: refused either way, the rest taken
    assert report.taken == ["102"] and "cannot be read" in report.problems["101"]


# --- wrong input ---------------------------------------------------------------------------------------------------

def test_wrong_format_is_a_course_error_naming_the_format(tmp_path):
    src = write_zip(tmp_path / "moodle.zip", {"Ann Lee_5501_assignsubmission_file_/ws.zip": zip_bytes(WORKSPACE)})
    with pytest.raises(CourseError) as exc:
        intake(src, "canvas", tmp_path / "staging")
    assert "not a Canvas download" in exc.value.message and "--from moodle" in exc.value.hint
    (tmp_path / "x.zip").write_text("not a zip")
    with pytest.raises(CourseError, match="not a readable .zip"):
        intake(tmp_path / "x.zip", "canvas", tmp_path / "staging2")


def test_bad_arguments(tmp_path):
    src = canvas_zip(tmp_path / "s.zip")
    with pytest.raises(CourseError, match="unknown intake format"):
        intake(src, "sakai", tmp_path / "staging")
    with pytest.raises(CourseError, match="no time zone"):
        intake(src, "git", tmp_path / "staging", before=datetime(2026, 1, 1))
    with pytest.raises(CourseError, match="overlaps"):
        intake(tmp_path, "folder", tmp_path / "staging")
    # grading an earlier intake's folder as a plain folder never empties that intake
    report = intake(src, "canvas", tmp_path / "out" / "intake")
    with pytest.raises(CourseError, match="overlaps"):
        intake(report.folder, "folder", tmp_path / "out" / "intake")
    assert sorted(p.name for p in report.folder.iterdir()) == ["101", "102", "103"]
    with pytest.raises(CourseError, match="no intake.json"):
        load_intake(tmp_path)
    assert parse_deadline("2026-03-01T23:59:00Z") == datetime(2026, 3, 1, 23, 59, tzinfo=timezone.utc)
    with pytest.raises(CourseError, match="no time zone"):
        parse_deadline("2026-03-01T23:59")
    with pytest.raises(CourseError, match="not an ISO 8601"):
        parse_deadline("tomorrow")


def test_folder_format_records_today_s_layout(tmp_path):
    subs = tmp_path / "subs"
    (subs / "alice" / "src").mkdir(parents=True)
    (subs / "bob.zip").write_bytes(zip_bytes(WORKSPACE))
    (subs / "carol.txt").write_text("x")
    report = intake(subs, "folder", tmp_path / "out" / "intake")
    assert report.folder == subs and list(report.records) == ["alice", "bob", "carol.txt"]
    assert report.records["bob"].submitted_at is None and report.records["bob"].source == str(subs / "bob.zip")
    assert "not a folder" in report.records["carol.txt"].problem
    assert [p.name for p in (tmp_path / "out" / "intake").iterdir()] == ["intake.json"]


# --- the command line ----------------------------------------------------------------------------------------------

def _error_lines(stderr: str) -> list[str]:
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert "Traceback" not in stderr
    return lines


def test_cli_grade_before_without_time_zone_is_one_line_error(tmp_path):
    from conftest import run_cli_in_process

    src = canvas_zip(tmp_path / "s.zip")
    proc = run_cli_in_process("grade", src, "--from", "canvas", "--before", "2026-03-01T23:59", "--lesson",
                              "print-forever-node", "--out", tmp_path / "out")
    assert proc.returncode == 5
    lines = _error_lines(proc.stderr)
    assert lines[0].startswith("error: --before '2026-03-01T23:59' has no time zone") and len(lines) == 2
    assert lines[1].startswith("hint: ")
    assert not (tmp_path / "out").exists()


def test_cli_grade_wrong_format_is_one_line_error(tmp_path):
    from conftest import run_cli_in_process

    src = write_zip(tmp_path / "moodle.zip", {"Ann Lee_5501_assignsubmission_file_/ws.zip": zip_bytes(WORKSPACE)})
    proc = run_cli_in_process("grade", src, "--from", "canvas", "--lesson", "print-forever-node",
                              "--out", tmp_path / "out")
    assert proc.returncode == 5
    lines = _error_lines(proc.stderr)
    assert lines[0].startswith("error: moodle.zip is not a Canvas download") and len(lines) == 2
    assert "--from moodle" in lines[1]
    proc = run_cli_in_process("grade", src, "--from", "sakai", "--lesson", "print-forever-node",
                              "--out", tmp_path / "out2")
    assert proc.returncode == 5 and "--from" in proc.stderr and "canvas" in proc.stderr
