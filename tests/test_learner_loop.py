"""The learner's loop: ``watch`` driven in a pseudo-terminal (pexpect), ``show``, ``list``'s files, ``check --all``.

terminal-basics is the lesson: it needs no build, so these tests exercise the
loop (file events, keys, child checks, cleanup, regressions) rather than ROS.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pexpect
import psutil
import pytest

from ros2course.watch import MARKER_VAR


def _run(ws: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ros2course", *args], cwd=ws, capture_output=True, text=True,
                          timeout=120, check=False, stdin=subprocess.DEVNULL, env={**os.environ, "COLUMNS": "200"})


def _write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")


def _marked_processes() -> list[int]:
    """PIDs of processes that inherited a watcher's marker (none may outlive the watcher)."""
    found = []
    for proc in psutil.process_iter(["pid"]):
        try:
            with open(f"/proc/{proc.pid}/environ", "rb") as handle:
                if f"{MARKER_VAR}=".encode() in handle.read():
                    found.append(proc.pid)
        except OSError:
            continue
    return found


@pytest.fixture
def ws(tmp_path: Path) -> Path:
    assert _run(tmp_path, "init", "ws").returncode == 0
    root = tmp_path / "ws"
    assert _run(root, "next").returncode == 0  # terminal-basics, the first lesson
    return root


def _answer(ws: Path, stuff: str = "stuff") -> Path:
    """The terminal-basics answer, as its commands would leave it (``stuff`` is the word the file holds)."""
    lesson = ws / "terminal_basics"
    (lesson / "a_folder").mkdir(parents=True, exist_ok=True)
    _write(lesson / "a_folder" / "an_empty_file.txt", "")
    _write(lesson / "file_with_stuff.txt", f"{stuff}\n")
    _write(lesson / "appended.txt", "first line\nsecond line\n")
    _write(lesson / "result_of_ls.txt", "\n".join(sorted([*(p.name for p in lesson.iterdir()), "result_of_ls.txt"])) + "\n")
    return lesson


def test_show_renders_instructions_and_touches_nothing(ws: Path):
    before = {p: p.stat().st_mtime_ns for p in ws.rglob("*")}
    proc = _run(ws, "show")
    assert proc.returncode == 0, proc.stderr
    assert "Files and folders from the terminal" in proc.stdout
    assert "Your files: terminal_basics" in proc.stdout
    other = _run(ws, "show", "python-asyncio")
    assert other.returncode == 0 and "asyncio" in other.stdout
    assert {p: p.stat().st_mtime_ns for p in ws.rglob("*")} == before


def test_list_names_where_each_lessons_files_are(ws: Path):
    proc = _run(ws, "list")
    assert proc.returncode == 0, proc.stderr
    row = next(line for line in proc.stdout.splitlines() if " terminal-basics " in line)
    assert "terminal_basics/" in row
    row = next(line for line in proc.stdout.splitlines() if " print-forever-node " in line)
    assert "src/python_package_with_a_node" in row


def test_check_all_reports_a_regression(ws: Path):
    nothing = _run(ws, "check", "--all")
    assert nothing.returncode == 0 and "No lesson passed yet" in nothing.stdout
    _answer(ws)
    assert _run(ws, "check").returncode == 0
    still = _run(ws, "check", "--all")
    assert still.returncode == 0, still.stdout + still.stderr
    assert "still passes" in still.stdout and "All 1 passed lessons still pass" in " ".join(still.stdout.split())
    _write(ws / "terminal_basics" / "file_with_stuff.txt", "nothing\n")
    broken = _run(ws, "check", "--all")
    assert broken.returncode == 1, broken.stdout + broken.stderr
    assert "REGRESSION" in broken.stdout and "terminal-basics" in broken.stdout
    both = _run(ws, "check", "--all", "terminal-basics")
    assert both.returncode == 5 and "--all" in both.stderr


def test_watch_rechecks_on_save_and_takes_keys(ws: Path):
    before = set(_marked_processes())
    lesson = ws / "terminal_basics"
    child = pexpect.spawn(sys.executable, ["-m", "ros2course", "watch"], cwd=str(ws), encoding="utf-8",
                          timeout=90, dimensions=(50, 160), env={**os.environ, "TERM": "xterm"})
    try:
        child.expect("watching terminal-basics")
        child.expect(r"\d+/\d+")  # the first verdict: the starter alone does not pass
        # a broken answer: the file holds the wrong word
        (lesson / "a_folder").mkdir(parents=True, exist_ok=True)
        _write(lesson / "a_folder" / "an_empty_file.txt", "")
        _write(lesson / "file_with_stuff.txt", "stuf\n")
        _write(lesson / "appended.txt", "first line\nsecond line\n")
        _write(lesson / "result_of_ls.txt", "\n".join(sorted(p.name for p in lesson.iterdir())) + "\n")
        child.expect("changed: ")
        child.expect("file_with_stuff.txt")
        child.expect(r"✗|FAIL|failed|lost", timeout=90)
        assert "Full marks" not in child.before
        # the fix
        _write(lesson / "file_with_stuff.txt", "stuff\n")
        child.expect("Full marks", timeout=90)
        child.send("h")
        child.expect(r"Hint 1/\d+")
        child.send("n")
        child.expect("watching python-minimalist-package")
        child.send("q")
        child.expect("watch ended")
        child.expect(pexpect.EOF, timeout=20)
    finally:
        child.close(force=True)
    assert child.exitstatus == 0, child.before
    assert set(_marked_processes()) - before == set(), "a process of the watcher outlived it"
    progress = _run(ws, "list")
    assert "done" in progress.stdout


def test_watch_needs_a_current_lesson(tmp_path: Path):
    assert _run(tmp_path, "init", "ws").returncode == 0
    proc = _run(tmp_path / "ws", "watch")
    assert proc.returncode == 5, proc.stderr
    assert "no current lesson" in proc.stderr and "hint:" in proc.stderr
