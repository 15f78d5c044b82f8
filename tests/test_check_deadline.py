"""A check that hangs ends at its deadline: the stacks written, every process it started killed, one error line,
exit status 6 (grader error), nothing recorded (ros2course.grade.deadline)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import psutil
import pytest

from ros2course.grade.deadline import CHECK_DEADLINE, DEADLINE_VAR, deadline_seconds


def _gone(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return True


def test_a_hung_block_ends_at_its_deadline_with_its_children(tmp_path) -> None:
    """A block stuck past its deadline: the process exits 6 with the error and hint, the stacks file shows where
    the main thread was, and a child started in a session of its own (as learner processes are) is killed."""
    script = textwrap.dedent("""
        import subprocess, sys, time
        from pathlib import Path
        from ros2course.grade.deadline import check_deadline
        child = subprocess.Popen(["sleep", "60"], start_new_session=True)
        print(child.pid, flush=True)
        def stuck_in_the_grader():
            time.sleep(60)
        with check_deadline("the check of print-forever-node", Path(sys.argv[1]), 1.0):
            stuck_in_the_grader()
        """)
    proc = subprocess.run([sys.executable, "-c", script, str(tmp_path / "logs")], capture_output=True, text=True,
                          timeout=30, check=False)
    assert proc.returncode == 6, proc.stderr
    lines = proc.stderr.splitlines()
    assert lines[0].startswith("error: the check of print-forever-node ran past its 1-s deadline and was stopped")
    assert lines[1].startswith("hint: run the check again")
    stacks = list((tmp_path / "logs").glob("hung-check-*.txt"))
    assert len(stacks) == 1 and str(stacks[0]) in lines[0]
    assert "in stuck_in_the_grader" in stacks[0].read_text()
    child = int(proc.stdout.split()[0])
    assert _gone(child), "the process the block started survived the deadline"


def test_a_block_that_ends_in_time_is_left_alone(tmp_path) -> None:
    """The timer is cancelled when the block ends: nothing is written, the process goes on."""
    script = textwrap.dedent("""
        import sys, time
        from pathlib import Path
        from ros2course.grade.deadline import check_deadline
        with check_deadline("the check of x", Path(sys.argv[1]), 0.5):
            pass
        time.sleep(1.0)
        print("still here")
        """)
    proc = subprocess.run([sys.executable, "-c", script, str(tmp_path / "logs")], capture_output=True, text=True,
                          timeout=30, check=False)
    assert proc.returncode == 0 and proc.stdout.strip() == "still here" and not (tmp_path / "logs").exists()


def test_the_deadline_is_read_from_the_environment(monkeypatch) -> None:
    monkeypatch.setenv(DEADLINE_VAR, "42")
    assert deadline_seconds() == 42.0
    for bad in ("", "soon", "0", "-5"):
        monkeypatch.setenv(DEADLINE_VAR, bad)
        assert deadline_seconds() == CHECK_DEADLINE


@pytest.mark.ros
def test_ros2course_check_that_runs_past_its_deadline_records_nothing(solution_workspace) -> None:
    """`ros2course check` under a deadline shorter than the check: exit 6, the one-line error, the progress file
    untouched, and no process of the check (colcon, the learner's node) left."""
    ws = solution_workspace
    before = ws.progress_path.read_bytes()
    proc = subprocess.run([sys.executable, "-m", "ros2course", "check", "print-forever-node", "--workspace",
                           str(ws.root)], capture_output=True, text=True, timeout=120, check=False,
                          env={**os.environ, DEADLINE_VAR: "2"})
    assert proc.returncode == 6, proc.stderr[-2000:]
    assert "error: the check of print-forever-node ran past its 2-s deadline" in proc.stderr
    assert ws.progress_path.read_bytes() == before
    left = []
    for other in psutil.process_iter(["cmdline"]):
        if any(str(ws.root) in part for part in other.info["cmdline"] or ()) and not _gone(other.pid):
            left.append(other.info["cmdline"])
    assert not left, left
