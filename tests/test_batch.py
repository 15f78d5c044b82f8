"""Batch grading without ROS nodes: submissions and archives, gradebook exports, resume, bad input.

(The tests that start real nodes are in test_batch_ros.py.)
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import os
import shutil
import tarfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest

from ros2course.batch.archive import Submission, discover, prepare
from ros2course.batch.runner import run_batch
from ros2course.errors import CourseError, NotGradable
from ros2course.grade.results import LessonResult
from ros2course.lesson.catalog import load_catalog
from ros2course.report import gradebook
from tests.conftest import SOLUTIONS

PKG = "python_package_with_a_node"


def _workspace(root: Path) -> Path:
    shutil.copytree(SOLUTIONS / PKG, root / "src" / PKG, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    return root


def _zip_dir(folder: Path, archive: Path, prefix: str = "") -> Path:
    with zipfile.ZipFile(archive, "w") as zf:
        for path in sorted(folder.rglob("*")):
            zf.write(path, prefix + str(path.relative_to(folder)))
    return archive


# --- archives and entries -------------------------------------------------------------------------

def test_entries_and_student_ids(tmp_path: Path) -> None:
    subs = tmp_path / "subs"
    _workspace(subs / "alice")
    (subs / "bob.zip").write_bytes(b"x")
    (subs / "carol.tar.gz").write_bytes(b"x")
    (subs / "notes.txt").write_text("hi")
    (subs / ".DS_Store").write_text("")
    found = {s.student: s for s in discover(subs)}
    assert sorted(found) == ["alice", "bob", "carol", "notes.txt"]
    assert found["notes.txt"].problem and not found["alice"].problem


def test_zip_and_tar_gz_and_folder_of_packages(tmp_path: Path) -> None:
    ws = _workspace(tmp_path / "alice")
    _zip_dir(ws, tmp_path / "zipped.zip", prefix="alice/")  # wrapped in a folder: descended into
    with tarfile.open(tmp_path / "tarred.tar.gz", "w:gz") as tf:
        tf.add(ws / "src", arcname="src")
    packages = tmp_path / "pkgs"
    shutil.copytree(ws / "src", packages)  # a folder of packages, no src/
    for name, entry in (("z", tmp_path / "zipped.zip"), ("t", tmp_path / "tarred.tar.gz"), ("p", packages)):
        root = prepare(Submission(name, entry), tmp_path / f"scratch-{name}")
        assert (root / "src" / PKG / "package.xml").is_file(), name
        assert (root / "src" / PKG / "setup.py").is_file(), name


def test_unreadable_and_unsafe_archives_are_not_gradable(tmp_path: Path) -> None:
    (tmp_path / "garbage.zip").write_bytes(b"not a zip")
    (tmp_path / "garbage.tar.gz").write_bytes(b"not a tar")
    with zipfile.ZipFile(tmp_path / "traversal.zip", "w") as zf:
        zf.writestr("src/ok.txt", "fine")
        zf.writestr("../../escaped.txt", "evil")
    with tarfile.open(tmp_path / "absolute.tar.gz", "w:gz") as tf:
        info = tarfile.TarInfo("/tmp/ros2course-escaped.txt")
        info.size = 4
        tf.addfile(info, io.BytesIO(b"evil"))
    with tarfile.open(tmp_path / "link.tar.gz", "w:gz") as tf:
        info = tarfile.TarInfo("src/passwd")
        info.type = tarfile.SYMTYPE
        info.linkname = "../../../etc/passwd"
        tf.addfile(info)
    (tmp_path / "empty").mkdir()
    reasons = {}
    for name in ("garbage.zip", "garbage.tar.gz", "traversal.zip", "absolute.tar.gz", "link.tar.gz", "empty"):
        with pytest.raises(NotGradable) as err:
            prepare(Submission(name, tmp_path / name), tmp_path / f"scratch-{name}")
        reasons[name] = err.value.message
    assert "unreadable .zip" in reasons["garbage.zip"]
    assert "unreadable .tar.gz" in reasons["garbage.tar.gz"]
    assert "unsafe archive member" in reasons["traversal.zip"] and "escaping" in reasons["traversal.zip"]
    assert "absolute path" in reasons["absolute.tar.gz"]
    assert "outside the archive" in reasons["link.tar.gz"]
    assert "no src/ folder" in reasons["empty"]
    assert not (tmp_path.parent / "escaped.txt").exists() and not Path("/tmp/ros2course-escaped.txt").exists()


def test_a_workspace_without_src_is_graded_for_a_lesson_without_packages(tmp_path: Path) -> None:
    """workspace-setup's hand-in is the workspace folder itself: one without src/ (its sources in source/) is
    graded as check grades it, and loses src_folder, instead of being not gradable (dev validate --batch of its
    fixture no-src-folder, fresh-clone rehearsal of f372114); a lesson with packages still refuses it."""
    from ros2course.batch.job import _packages_needed  # noqa: PLC0415

    entry = tmp_path / "bob"
    (entry / "source").mkdir(parents=True)
    (entry / "install").mkdir()
    assert not _packages_needed(["workspace-setup"]) and _packages_needed(["workspace-setup", "parameters"])
    assert _packages_needed(["no-such-lesson"])
    ws = prepare(Submission("bob", entry), tmp_path / "scratch", packages_needed=False)
    assert (ws / "source").is_dir() and (ws / "install").is_dir() and not (ws / "src").exists()
    with pytest.raises(NotGradable):
        prepare(Submission("bob", entry), tmp_path / "scratch-2")


# --- gradebook exports ----------------------------------------------------------------------------

def _record(student: str, status: str, checks: list[tuple[str, float, float, bool]], message: str = "") -> dict:
    """One ``results.jsonl`` line, as a batch writes it."""
    out = {"student": student, "lesson": "print-forever-node", "status": status,
           "score": sum(c[1] for c in checks), "max_score": 4.0,
           "checks": [{"id": i, "name": f"check {i}", "points": p, "max_points": m, "passed": ok,
                       "observed": f"saw {i}", "expected": f"want {i}", "hint": "" if ok else f"fix {i}"}
                      for i, p, m, ok in checks], "timings": {"total": 2.5}}
    if message:
        out["message"] = message
    return out


RECORDS = [LessonResult.from_record(r) for r in (
    _record("alice", "passed", [("a", 2, 2, True), ("b", 2, 2, True)]),
    _record("bob", "failed", [("a", 2, 2, True), ("b", 0, 2, False)]),
    _record("carol", "grader error", [("a", 0, 2, False), ("b", 0, 2, False)], "the grader failed: boom"),
    _record("dave", "not gradable", [], "colcon build failed\nline 2"),
)]


def test_a_record_round_trips_through_results_jsonl() -> None:
    """from_record(to_record(x)) == x, and the check --json shape is unchanged."""
    for result in RECORDS:
        assert LessonResult.from_record(json.loads(json.dumps(result.to_record()))) == result
    shape = RECORDS[1].to_json()
    assert list(shape) == ["lesson", "score", "max_score", "status", "checks"] and shape["status"] == "failed"
    assert list(shape["checks"][0]) == ["id", "name", "points", "max_points", "passed", "observed", "expected", "hint"]


def test_gradebook_csv_columns() -> None:
    rows = list(csv.DictReader(io.StringIO(gradebook.gradebook_csv(RECORDS, {"print-forever-node": ["a", "b"]}))))
    assert list(rows[0]) == ["student", "lesson", "score", "max_score", "status", "reason", "total", "total_max",
                             "a", "b"]
    by = {r["student"]: r for r in rows}
    assert by["alice"]["status"] == "graded" and by["alice"]["score"] == "4" and by["alice"]["b"] == "2"
    assert (by["alice"]["total"], by["alice"]["total_max"], by["dave"]["total"]) == ("4", "4", "0")
    assert by["bob"]["b"] == "0"
    assert by["carol"]["status"] == "grader error"
    assert by["dave"]["status"] == "not gradable" and by["dave"]["reason"] == "colcon build failed"
    assert by["dave"]["a"] == ""


def test_gradebook_total_across_lessons() -> None:
    """``total`` sums a student's points over every lesson, on each of their rows."""
    other = [dataclasses.replace(r, lesson="workspace-setup", score=1.0, max_score=5.0) for r in RECORDS[:2]]
    text = gradebook.gradebook_csv([*RECORDS, *other], {"print-forever-node": ["a", "b"], "workspace-setup": ["c"]})
    rows = list(csv.DictReader(io.StringIO(text)))
    alice = [r for r in rows if r["student"] == "alice"]
    assert len(alice) == 2 and {(r["total"], r["total_max"]) for r in alice} == {("5", "9")}
    assert "print-forever-node:a" in rows[0] and [r["total"] for r in rows if r["student"] == "dave"] == ["0"]


def test_jsonl_truncated_last_line(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    gradebook.append_record(path, RECORDS[0])
    with open(path, "a", encoding="utf-8") as handle:
        handle.write(json.dumps(RECORDS[1].to_record())[:40])  # a batch killed mid-write
    assert [r.student for r in gradebook.read_results(path)] == ["alice"]
    gradebook.append_record(path, RECORDS[2])
    assert [r.student for r in gradebook.read_results(path)] == ["alice", "carol"]
    lines = path.read_text().splitlines()
    assert json.loads(lines[-1])["student"] == "carol"


def test_gradescope_json_schema() -> None:
    data = gradebook.gradescope_json([RECORDS[1]])
    assert data["score"] == 2 and set(data) >= {"score", "output", "tests", "visibility", "execution_time"}
    for test in data["tests"]:
        assert set(test) >= {"name", "score", "max_score", "output", "visibility"}
    assert data["tests"][1]["score"] == 0 and "fix b" in data["tests"][1]["output"]
    broken = gradebook.gradescope_json([RECORDS[3]])
    assert broken["score"] == 0 and broken["tests"][0]["max_score"] == 4.0
    assert "colcon build failed" in broken["tests"][0]["output"]


def test_junit_failure_versus_error() -> None:
    root = ET.fromstring(gradebook.junit_xml(RECORDS))
    suites = {s.get("name"): s for s in root.iter("testsuite")}
    assert len(suites) == 4
    bob = suites["bob.print-forever-node"]
    assert bob.get("failures") == "1" and bob.get("errors") == "0" and bob.get("tests") == "2"
    assert [c.get("name") for c in bob.iter("testcase") if c.find("failure") is not None] == ["b"]
    carol = suites["carol.print-forever-node"]
    assert carol.get("errors") == "2" and carol.find(".//failure") is None
    dave = suites["dave.print-forever-node"]
    assert dave.get("failures") == "1" and dave.find(".//failure").get("message") == "colcon build failed"


# --- resume and bad input (a lesson without nodes: workspace-setup) ----------------------------------

def test_resume_skips_finished_and_tolerates_truncated_line(tmp_path: Path) -> None:
    subs = tmp_path / "subs"
    for name in ("alice", "bob"):
        (subs / name / "src").mkdir(parents=True)
    out = tmp_path / "out"
    out.mkdir()
    earlier = dict(_record("alice", "failed", [("src_folder", 1, 1, True)]), lesson="workspace-setup", score=1.0,
                   max_score=5.0)
    (out / "results.jsonl").write_text(json.dumps(earlier) + "\n" + json.dumps(earlier).replace("alice", "bob")[:30])
    with pytest.raises(CourseError, match="already holds results"):
        run_batch(subs, ["workspace-setup"], out, jobs=1)
    report = run_batch(subs, ["workspace-setup"], out, jobs=1, resume=True)
    assert report.skipped == 1 and report.graded_now == 1
    records = gradebook.read_results(out / "results.jsonl")
    assert [r.student for r in records] == ["alice", "bob"]
    assert records[0] == LessonResult.from_record(earlier)  # untouched
    assert records[1].status == "failed" and records[1].max_score == 5.0
    rows = list(csv.DictReader(open(out / "gradebook.csv", encoding="utf-8")))
    assert [r["student"] for r in rows] == ["alice", "bob"]
    assert (out / "bob" / "results.json").is_file() and (out / "bob" / "logs").is_dir()


def test_cli_bad_input_is_one_line(tmp_path: Path, cli) -> None:
    proc = cli("grade", str(tmp_path / "missing"), "--lesson", "workspace-setup", "--out", str(tmp_path / "o"))
    assert proc.returncode == 5 and "Traceback" not in proc.stderr
    assert "error:" in proc.stderr and "hint:" in proc.stderr
    (tmp_path / "subs").mkdir()
    proc = cli("grade", str(tmp_path / "subs"), "--lesson", "no-such-lesson", "--out", str(tmp_path / "o"))
    assert proc.returncode == 5 and "Traceback" not in proc.stderr
    proc = cli("grade", str(tmp_path / "subs"), "--lesson", "workspace-setup", "--out", str(tmp_path / "subs" / "o"))
    assert proc.returncode == 5 and "inside the submissions folder" in proc.stderr


def test_cli_grade_and_gradescope(tmp_path: Path, cli) -> None:
    """The two commands end to end on a lesson without nodes (workspace-setup)."""
    subs = tmp_path / "subs"
    (subs / "alice" / "src").mkdir(parents=True)
    (subs / "bob.zip").write_bytes(b"broken")
    proc = cli("grade", str(subs), "--lesson", "workspace-setup", "--out", str(tmp_path / "out"), "--jobs", "2")
    assert proc.returncode == 0, proc.stderr
    assert "score distribution" in proc.stderr and "not graded" in proc.stderr and "isolation" in proc.stderr
    rows = list(csv.DictReader(open(tmp_path / "out" / "gradebook.csv", encoding="utf-8")))
    assert [(r["student"], r["status"]) for r in rows] == [("alice", "graded"), ("bob", "not gradable")]

    upload = tmp_path / "autograder" / "submission"
    (upload / "src").mkdir(parents=True)
    results = tmp_path / "autograder" / "results" / "results.json"
    proc = cli("gradescope", "--submission", str(upload), "--results", str(results),
               env={"ROS2COURSE_LESSON": "workspace-setup"})
    assert proc.returncode == 0, proc.stderr
    data = json.loads(results.read_text())
    assert data["score"] >= 1 and [t["name"] for t in data["tests"]][0] == "The workspace has a src/ folder"
    proc = cli("gradescope", "--lesson", "no-such-lesson", "--submission", str(upload), "--results", str(results))
    assert proc.returncode == 5 and "Traceback" not in proc.stderr


# --- isolation (ros2course.sandbox) --------------------------------------------------------------


def test_command_is_unchanged_without_a_submission_identity() -> None:
    from ros2course import sandbox

    assert sandbox.current() is None
    assert sandbox.command(["/bin/true"], {"A": "1"}) == (["/bin/true"], {"A": "1"})


def test_command_drops_to_the_identity_and_keeps_the_learner_env_away_from_root() -> None:
    """The root side gets only PATH; LD_PRELOAD & co. reach the program only after the uid drop."""
    from ros2course import sandbox

    sandbox.configure(sandbox.SubmissionIdentity(1_900_000_123, 1_900_000_123, 99, "/sys/fs/cgroup/pids/x/cgroup.procs"))
    try:
        argv, env = sandbox.command(["/bin/prog", "--x"], {"LD_PRELOAD": "/ws/evil.so", "-bad": "1", "ROS_DOMAIN_ID": "7"},
                                    pdeathsig=True)
    finally:
        sandbox.configure(None)
    assert "LD_PRELOAD" not in env and set(env) <= {"PATH", "LANG"}
    drop = argv.index(next(a for a in argv if a.endswith("setpriv")))
    env_i = argv.index("-i")
    assert argv[drop:env_i] == [argv[drop], "--reuid=1900000123", "--regid=1900000123", "--clear-groups",
                                "--no-new-privs", "--inh-caps=-all", "--bounding-set=-all", "--pdeathsig", "KILL", "--",
                                *sandbox.parent_alive_guard(), "/usr/bin/env"]
    assert "--nproc=99:99" in argv[:drop] and "/sys/fs/cgroup/pids/x/cgroup.procs" in argv[:drop]
    assert argv[env_i + 1:] == ["LD_PRELOAD=/ws/evil.so", "ROS_DOMAIN_ID=7", "/bin/prog", "--x"]


def test_mount_plan_keeps_what_a_hidden_folder_holds_read_only(tmp_path: Path) -> None:
    from ros2course import sandbox

    home = tmp_path / "home"
    python = home / ".pyenv" / "3.11"
    python.mkdir(parents=True)
    plan = sandbox.MountPlan("/sbin/ip", own=str(tmp_path / "scratch"), hide=[str(tmp_path / "subs")],
                             read_only=[str(python)], keep=[], private_tmp=["/tmp"], hidden_home=str(home))
    script = plan.script()
    lines = script.splitlines()
    assert lines[0] == "set -e" and lines[-1] == 'exec "$@"'
    hide_home = next(i for i, line in enumerate(lines) if f"ros2course-hidden {home}" in line)
    restore = lines.index(f"mount --move /dev/shm/.ros2course-hold/1 {python}")
    assert restore > hide_home and lines[restore + 1] == f"mount -o remount,bind,ro {python}"
    assert "mount --bind /dev/null /etc/shadow" in script


def test_the_engine_an_editable_install_imports_stays_readable_in_a_job(tmp_path: Path, monkeypatch) -> None:
    """A checkout under /tmp installed with ``pip install -e``: the job's worker imports ``ros2course`` from the
    checkout, not the venv, and the job's private /tmp would hide it (a fresh clone in /tmp failed so)."""
    from pathlib import Path as P

    import ros2course
    from ros2course import sandbox

    monkeypatch.setattr(sandbox, "content_root", lambda: tmp_path)  # a course copied elsewhere (dev mutate's tests)
    engine = os.path.realpath(P(ros2course.__file__).parent)
    assert any(engine == p or engine.startswith(p.rstrip("/") + "/") for p in sandbox.read_only_paths(load_catalog().course.root))


def test_copy_logs_never_copies_links_or_fifos(tmp_path: Path) -> None:
    from ros2course import sandbox

    src, dest = tmp_path / "logs", tmp_path / "out"
    (src / "ros").mkdir(parents=True)
    (src / "node.log").write_text("hello")
    secret = tmp_path / "secret.txt"
    secret.write_text("grader secret")
    (src / "ros" / "link.log").symlink_to(secret)
    (src / "dirlink").symlink_to(tmp_path)
    os.mkfifo(src / "ros" / "pipe")
    skipped = sandbox.copy_logs(src, dest)
    assert (dest / "node.log").read_text() == "hello"
    assert not (dest / "ros" / "link.log").exists() and not (dest / "dirlink").exists()
    assert not (dest / "ros" / "pipe").exists()
    assert not any(p.is_symlink() for p in dest.rglob("*"))
    assert sorted(skipped) == ["dirlink: symbolic link", "ros/link.log: symbolic link", "ros/pipe: not a regular file"]
    assert "ros/link.log" in (dest / "ros2course-not-copied.txt").read_text()


def test_require_isolation_refuses_with_the_missing_protections(tmp_path: Path, monkeypatch) -> None:
    from ros2course.batch import job as one_job
    from ros2course.batch import runner as batch
    from ros2course import sandbox

    (tmp_path / "subs" / "alice" / "src").mkdir(parents=True)
    with pytest.raises(CourseError, match="missing network namespace .isolation turned off"):
        batch.run_batch(tmp_path / "subs", ["workspace-setup"], tmp_path / "out", isolate=False, require_isolation=True)
    caps = sandbox.Capabilities([], False, False, "", {sandbox.UID: "not root: test"}, {})
    monkeypatch.setattr(sandbox, "_caps", caps)
    with pytest.raises(CourseError, match=r"unprivileged uid \(not root: test\)"):
        batch.run_batch(tmp_path / "subs", ["workspace-setup"], tmp_path / "out", require_isolation=True)
    # the job itself refuses too (a Dask worker may be another machine): a grader error row, nothing run
    job = one_job.Job("b", "alice", str(tmp_path / "subs" / "alice"), "", ["workspace-setup"], str(tmp_path / "out2"),
                    require_isolation=True, course=str(load_catalog().course.root))
    outcome = one_job.run_job(job)
    record = outcome.records[0]
    assert record.status == "grader error" and "not root: test" in record.message
    assert record.isolation["missing"] == {sandbox.UID: "not root: test"}


def test_summary_lists_each_protection(tmp_path: Path) -> None:
    from rich.console import Console

    from ros2course.batch import runner as batch
    from ros2course import sandbox

    iso = sandbox.Isolation({sandbox.NETWORK: "loopback only"}, {sandbox.UID: "not root"}).to_json()
    report = batch.BatchReport(tmp_path, [], 0, 0, 0.0, iso, [])
    console = Console(file=io.StringIO(), width=160)
    batch.render_summary(report, console)
    text = console.file.getvalue()
    assert "network namespace" in text and "loopback only" in text
    assert "unprivileged uid" in text and "MISSING" in text and "not root" in text


def test_relocate_paths_names_the_workers_folders_as_the_instructor_sees_them(tmp_path: Path) -> None:
    """Field by field, on path boundaries: ``scratch/ws2`` is not ``scratch/ws``; quotes and backslashes
    in a text survive (the old rewrite replaced inside serialised JSON)."""
    from ros2course.batch.job import relocate_paths
    from ros2course.grade.results import CheckResult, LessonResult, Status

    scratch = tmp_path / "ros2course-grade-alice"
    result = LessonResult("l", 1.0, 2.0, Status.FAILED, [
        CheckResult("build", "b", 1, 1, True, f'built "{scratch}/ws/src" (a \\ b)', "", ""),
        CheckResult("run", "r", 0, 1, False, f"see {scratch}/logs/node.log; kept {scratch}/ws2/x",
                    "", f"full log: {scratch}/logs")],
        f"colcon failed in {scratch}/ws", log_dir=str(scratch / "logs" / "l"),
        build={"log": str(scratch / "logs" / "build.log"), "ok": True})
    out = relocate_paths([result], [(scratch / "logs", "/out/alice/logs"), (scratch / "ws", "<submission>"),
                                    (scratch, "<scratch>")])[0]
    assert out.log_dir == "/out/alice/logs/l"
    assert out.checks[0].observed == 'built "<submission>/src" (a \\ b)'
    assert out.checks[1].observed == "see /out/alice/logs/node.log; kept <scratch>/ws2/x"
    assert out.checks[1].hint == "full log: /out/alice/logs"
    assert out.message == "colcon failed in <submission>"
    assert out.build == {"log": "/out/alice/logs/build.log", "ok": True}
    assert (out.score, out.status, out.checks[1].passed) == (1.0, Status.FAILED, False)


def test_a_job_that_raises_is_a_grader_error_row_and_tells_nothing_of_the_walls(tmp_path: Path, monkeypatch) -> None:
    """A fault of the grading machine in one job (run_job raised) gives that student a "grader error" row per
    lesson; the batch's isolation summary keeps what the jobs that ran reported (issue 23: typed isolation)."""
    import concurrent.futures as cf

    from ros2course.batch import runner as batch
    from ros2course.batch.job import JobResult
    from ros2course import sandbox

    for name in ("alice", "bob"):
        (tmp_path / "subs" / name / "src").mkdir(parents=True)
    walls = sandbox.Isolation({sandbox.NETWORK: "loopback only"}, {}, memory="none", pids_stats={"peak": 3},
                              killed_after=2)

    def fake_job(job):
        if job.student == "bob":
            raise OSError("no space left on device")
        result = batch.unfinished_result(job.lessons[0], "failed", "graded")
        result.student, result.isolation = job.student, walls.to_json()
        return JobResult(job.student, [result], walls)

    monkeypatch.setattr(batch, "run_job", fake_job)
    with cf.ThreadPoolExecutor(max_workers=1) as pool:
        report = batch.run_batch(tmp_path / "subs", ["workspace-setup"], tmp_path / "out", executor=pool)
    rows = {r.student: r for r in gradebook.read_results(tmp_path / "out" / "results.jsonl")}
    assert rows["bob"].status == "grader error" and "OSError: no space left on device" in rows["bob"].message
    assert rows["alice"].status == "failed"
    assert report.isolation["protections"] == {sandbox.NETWORK: "loopback only"}
    assert (report.isolation["memory"], report.isolation["pids_peak"], report.isolation["killed_after"]) == ("none", 3, 2)
    assert sandbox.Isolation.never_ran("not run (not gradable)").to_json() == {
        "netns": False, "mountns": False, "reason": "not run (not gradable)"}


def test_a_batch_hides_the_shared_reference_builds_and_the_authors_folders(tmp_path: Path) -> None:
    """The venv is read-only but visible to a submission; its shared reference builds hold reference sources,
    so they are hidden, and so are the course's .git, docs, tests and benchmarks (solutions/ too)."""
    from ros2course.batch.runner import default_hidden
    from ros2course.builder.reference import reference_cache_folder
    from ros2course.lesson.catalog import content_root

    reference_cache_folder().mkdir(parents=True, exist_ok=True)
    hidden = default_hidden(load_catalog().course, tmp_path / "subs", tmp_path / "out", tmp_path / "scratch")
    assert str(reference_cache_folder().resolve()) in hidden
    root = content_root()
    for name in ("solutions", "docs", "tests", "benchmarks", ".git"):
        if (root / name).is_dir():
            assert str((root / name).resolve()) in hidden, name
    assert str((root / "graders").resolve()) not in hidden and str((root / "chapters").resolve()) not in hidden


def test_one_set_of_walls_serves_grade_and_gradescope(tmp_path: Path, monkeypatch) -> None:
    """``submission_walls`` is what every job of a batch carries: the hidden folders and, masked, every lesson's
    mutation record; a job's mount plan masks exactly those beside the machine's secrets."""
    from ros2course import sandbox
    from ros2course.batch import gradescope, job as job_mod, runner
    from ros2course.lesson.catalog import load_catalog

    walls = runner.submission_walls(load_catalog().course, tmp_path / "subs", tmp_path / "out", tmp_path / "scratch")
    assert walls.hide == runner.default_hidden(load_catalog().course, tmp_path / "subs", tmp_path / "out", tmp_path / "scratch")
    records = [lesson.folder / runner.MUTATION_RECORD for lesson in load_catalog().lessons]
    assert walls.masked == sorted(str(p) for p in records if p.is_file()) and walls.masked
    assert "submission_walls" in gradescope.run_gradescope.__code__.co_names
    can_unshare = bool(sandbox.capabilities().unshare)  # probed (with a real mount plan) before the plan is replaced
    plans = []

    class Planned(Exception):
        pass

    def plan(*args, **kwargs):
        plans.append(kwargs)
        raise Planned  # the plan is what is checked; nothing is mounted

    monkeypatch.setattr(sandbox, "MountPlan", plan)
    job = job_mod.Job("b", "s", str(tmp_path), "", ["print-forever-node"], str(tmp_path / "out"),
                      hide=walls.hide, masked=walls.masked, course=str(load_catalog().course.root))
    (tmp_path / "scratch").mkdir()
    if can_unshare:
        with pytest.raises(Planned):
            job_mod.job_walls(job, tmp_path / "scratch")
        assert plans[0]["secrets"] == sandbox.SECRETS + tuple(walls.masked)
        assert plans[0]["hide"] == walls.hide
