"""Batch grading with real ROS 2 nodes: cross-talk, a hostile submission, a class of 20, Dask.

Submissions are generated from the reference solution and the lessons' wrong
fixtures (tests/fixtures), as ``dev validate`` materialises them.
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import re
import shutil
import tempfile
import time
from pathlib import Path

import psutil
import pytest

from ros2course.batch.job import BATCH_MARKER_VAR
from ros2course.batch.runner import run_batch
from ros2course.grade.engine import grade_lesson
from ros2course.dev.validate import (
    apply_edits,
    load_fixtures,
    reference_workspace,
    run_commands,
)
from ros2course.lesson.catalog import load_catalog
from ros2course.report import gradebook
from tests.conftest import cpu_lock

#: whole classes graded two at a time: never beside each other (conftest.cpu_exclusive)
pytestmark = [pytest.mark.ros, pytest.mark.usefixtures("cpu_exclusive"), pytest.mark.timeout(1200)]

PKG = "python_package_with_a_node"
NODE_FILE = f"src/{PKG}/{PKG}/print_forever_node.py"


def tree_digest(folder: Path) -> str:
    """Hash of every path, mode and content under ``folder`` (byte-for-byte comparison)."""
    digest = hashlib.sha256()
    for path in sorted(folder.rglob("*")):
        stat = path.lstat()
        digest.update(f"{path.relative_to(folder)}\0{stat.st_mode}\0".encode())
        if path.is_file() and not path.is_symlink():
            digest.update(path.read_bytes())
    return digest.hexdigest()


def verdict(record) -> tuple[str, tuple[str, ...]]:
    """What must match between batch and one-by-one: status and the checks that lost points."""
    return record.status.value, tuple(c.id for c in record.checks if c.points < c.max_points)


def make_submission(lesson_id: str, dest: Path, fixture=None) -> Path:
    """The reference workspace of ``lesson_id`` (plus a fixture's edits) at ``dest``, as a learner leaves it."""
    lesson = load_catalog().get(lesson_id)
    reference_workspace(lesson, dest)
    if fixture is not None:
        apply_edits(dest, fixture.edits)
    commands = lesson.reference.commands if fixture is None or fixture.commands is None else fixture.commands
    run_commands(dest, commands)
    return dest


def _stale_new_shm(before: set[str]) -> list[str]:
    """New Fast DDS lock files in /dev/shm that nobody holds (i.e. left by a dead process)."""
    stale = []
    for name in sorted(set(os.listdir("/dev/shm")) - before):
        if not (name.startswith("fastrtps_") and name.endswith("_el")):
            continue
        try:
            fd = os.open(f"/dev/shm/{name}", os.O_RDWR)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            stale.append(name)
        except OSError:
            pass
        finally:
            os.close(fd)
    return stale


def test_cross_talk_two_at_once(tmp_path: Path) -> None:
    """A correct print-forever and one logging other text, graded at the same time: each gets its own score."""
    subs = tmp_path / "subs"
    make_submission("print-forever-node", subs / "alice")
    bob = make_submission("print-forever-node", subs / "bob")
    node = bob / NODE_FILE
    node.write_text(node.read_text().replace("Printed {self.print_count} times.", "Printed {self.print_count} times!"))
    shutil.make_archive(str(subs / "carol"), "gztar", subs / "alice")  # an archive of the same workspace
    before = tree_digest(subs)
    out = tmp_path / "out"
    report = run_batch(subs, ["print-forever-node"], out, jobs=2)
    assert tree_digest(subs) == before, "the submissions folder was modified"
    by = {r.student: r for r in report.records}
    assert by["alice"].status == "passed" and by["alice"].score == 15, by["alice"]
    assert by["carol"].status == "passed", by["carol"]
    assert by["bob"].status == "failed"
    assert verdict(by["bob"])[1] == ("log_format", "counts_from_zero", "rate"), by["bob"]
    # the outputs, written as each finished
    lines = gradebook.read_results(out / "results.jsonl")
    assert sorted(r.student for r in lines) == ["alice", "bob", "carol"]
    assert all(r.timings.get("total") and r.isolation for r in lines)
    header = (out / "gradebook.csv").read_text().splitlines()[0].split(",")
    assert header[:6] == ["student", "lesson", "score", "max_score", "status", "reason"] and "sigint_exit" in header
    assert (out / "alice" / "results.json").is_file() and (out / "junit.xml").is_file()
    assert (out / "bob" / "logs" / "print-forever-node" / "print_forever_node.stdout.log").is_file()
    assert str(out / "bob" / "logs") in by["bob"].log_dir
    # the recording of bob's check stays with his logs, and his failed checks name it
    recording = out / "bob" / "logs" / "print-forever-node" / "observed.mcap"
    assert recording.is_file() and recording.stat().st_size > 0
    failed = [c for c in by["bob"].checks if not c.passed and not c.skipped]
    assert failed and all(c.evidence and c.evidence["recording"] == str(recording) for c in failed), failed
    if not report.isolation.get("netns"):
        pytest.skip(f"graded without network namespaces: {report.isolation.get('reason')}")


def test_an_unchanged_interface_package_is_taken_from_the_courses_build(tmp_path: Path) -> None:
    """parameters builds on custom-interfaces' package_with_interfaces: a hand-in holding it exactly as the
    course has it is built against the course's build of it (rosidl is most of a hand-in's build); one
    byte changed there (a comment in the message file) and the hand-in's own copy is built. Same verdicts."""
    subs = tmp_path / "subs"
    make_submission("parameters", subs / "alice")
    bob = make_submission("parameters", subs / "bob")
    msg = bob / "src/package_with_interfaces/msg/AmazingQuote.msg"
    msg.write_text(msg.read_text() + "# bob was here\n")
    report = run_batch(subs, ["parameters"], tmp_path / "out", jobs=2)
    by = {r.student: r for r in report.records}
    assert [(by[s].status, by[s].score) for s in ("alice", "bob")] == [("passed", by["alice"].max_score)] * 2, by
    assert by["alice"].build.get("prebuilt") == ["package_with_interfaces"], by["alice"].build
    assert "prebuilt" not in by["bob"].build, by["bob"].build
    bob_log = Path(by["bob"].build["log"]).read_text()
    assert "Finished <<< package_with_interfaces" in bob_log
    assert "Starting >>> package_with_interfaces" not in Path(by["alice"].build["log"]).read_text()


HOSTILE = '''
import os, signal, sys, time


def main(args=None):
    import rclpy
    rclpy.init(args=args)
    node = rclpy.create_node('print_forever')  # a node, never a log record
    for i in range(3):
        if os.fork() == 0:
            if i == 0:
                os.setsid()  # escapes the process group
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
            print(f'started {os.getpid()}', flush=True)
            while True:
                time.sleep(0.2)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    print(f'started {os.getpid()}', flush=True)
    while True:
        time.sleep(0.2)
'''


def processes_mentioning(needle: str) -> list[str]:
    """Live processes on this machine whose command line or environment mentions ``needle``."""
    found = []
    for proc in psutil.process_iter(["pid"]):
        if proc.pid == os.getpid():
            continue
        try:
            blob = Path(f"/proc/{proc.pid}/cmdline").read_bytes() + Path(f"/proc/{proc.pid}/environ").read_bytes()
            if needle.encode() in blob and proc.status() != psutil.STATUS_ZOMBIE:
                found.append(f"{proc.pid} {' '.join(proc.cmdline())[:160]}")
        except (OSError, psutil.Error):
            continue
    return found


def wait_until_gone(needle: str, seconds: float = 5.0) -> list[str]:
    """Processes mentioning ``needle`` still alive after waiting up to ``seconds`` for them to be reaped."""
    deadline = time.monotonic() + seconds
    alive = processes_mentioning(needle)
    while alive and time.monotonic() < deadline:
        time.sleep(0.1)
        alive = processes_mentioning(needle)
    return alive


def test_hostile_submission_times_out_and_leaves_nothing(tmp_path: Path) -> None:
    """A node that ignores SIGINT/SIGTERM and forks such children is stopped at the timeout; nothing survives."""
    subs = tmp_path / "subs"
    ws = make_submission("print-forever-node", subs / "mallory")
    (ws / NODE_FILE).write_text(HOSTILE)
    shm_before = set(os.listdir("/dev/shm"))
    report = run_batch(subs, ["print-forever-node"], tmp_path / "out", jobs=1, timeout=8)
    record = report.records[0]
    assert record.status == "not gradable" and record.message == "timed out after 8 s", record
    log = tmp_path / "out" / "mallory" / "logs" / "print-forever-node" / "print_forever_node.stdout.log"
    # four processes share the pipe: print()'s text and newline can interleave, so count the pids
    started = re.findall(r"started (\d+)", log.read_text()) if log.exists() else []
    assert len(started) == 4, f"the hostile node did not start its children in time: {started}"
    alive = wait_until_gone("ros2course-grade-mallory")
    assert not alive, f"processes of the submission survived: {alive}"
    marked = []
    for proc in psutil.process_iter(["pid"]):
        try:
            with open(f"/proc/{proc.pid}/environ", "rb") as handle:
                environ = handle.read()
        except OSError:
            continue
        # other tests may be grading a batch at the same time (xdist): only this job's processes
        # have a HOME in mallory's scratch folder (no other test grades a student of that name)
        if BATCH_MARKER_VAR.encode() in environ and b"/ros2course-grade-mallory-" in environ:
            marked.append(proc.pid)
    assert not marked, f"processes carrying the batch marker survived: {marked}"
    assert not _stale_new_shm(shm_before)
    gs = gradebook.read_results(tmp_path / "out" / "results.jsonl")
    assert gs and gs[0].status == "not gradable"


@pytest.fixture(scope="module")
def template_class(tmp_path_factory):
    """20 python-node-template submissions (reference and every wrong fixture, round robin) + one-by-one verdicts."""
    root = tmp_path_factory.mktemp("class")
    variants = {"reference": None, **{f.name: f for f in load_fixtures("python-node-template")}}
    built = {name: make_submission("python-node-template", root / "variants" / name, fixture)
             for name, fixture in variants.items()}
    lesson = load_catalog().get("python-node-template")
    expected = {}
    with cpu_lock():  # a module fixture runs before the function-scoped cpu_exclusive
        for name, folder in built.items():  # one by one, as `check` grades them
            copy = Path(tempfile.mkdtemp(prefix="ros2course-onebyone-"))
            try:
                shutil.copytree(folder, copy / "ws", symlinks=True)
                expected[name] = verdict(grade_lesson(lesson, copy / "ws"))
            finally:
                shutil.rmtree(copy, ignore_errors=True)
    subs = root / "subs"
    names = list(built)
    assignment = {}
    for i in range(20):
        name = names[i % len(names)]
        student = f"s{i:02d}"
        shutil.copytree(built[name], subs / student, symlinks=True)
        assignment[student] = name
    return subs, assignment, expected


def test_class_of_20_same_verdicts_as_one_by_one(template_class, tmp_path: Path) -> None:
    subs, assignment, expected = template_class
    assert len(assignment) == 20 and len(set(expected.values())) > 3
    before = tree_digest(subs)
    report = run_batch(subs, ["python-node-template"], tmp_path / "out", jobs=2)
    assert tree_digest(subs) == before
    got = {r.student: verdict(r) for r in report.records}
    mismatches = {s: (assignment[s], got.get(s), expected[assignment[s]]) for s in assignment
                  if got.get(s) != expected[assignment[s]]}
    assert not mismatches, mismatches


def test_dask_local_cluster(template_class, tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed", reason="Dask is an optional extra: pip install 'ros2course[dask]'")
    subs, assignment, expected = template_class
    two = tmp_path / "subs"
    picked = ["s00", "s01"]
    for student in picked:
        shutil.copytree(subs / student, two / student, symlinks=True)
    with distributed.LocalCluster(processes=False, n_workers=1, threads_per_worker=2, dashboard_address=None) as cluster:
        report = run_batch(two, ["python-node-template"], tmp_path / "out", scheduler=cluster.scheduler_address)
    got = {r.student: verdict(r) for r in report.records}
    assert got == {s: expected[assignment[s]] for s in picked}
    assert len(gradebook.read_results(tmp_path / "out" / "results.jsonl")) == 2
