"""Kit steps for learner programs that are not ROS nodes: scripts, compiled binaries, pip.

They run through :meth:`GradingSession.start_program`: own process group,
capped output, a deadline, nothing left running (the brief's "bad input"
rules apply to every learner program, not only to nodes).
"""

from __future__ import annotations

import dataclasses
import os
import signal
import time
from pathlib import Path

from course.grade.engine import GradingSession
from course.run.probes import wait_until


@dataclasses.dataclass(frozen=True)
class ProgramRun:
    """What a finished (or stopped) learner program did.

    Attributes:
        returncode: exit code (negative: killed by that signal; None: never started).
        stdout, stderr: captured text (capped).
        timed_out: it was still running at the timeout and was stopped.
        seconds: wall time from start to exit or stop.
        traceback: the last Python traceback in its output, "" if none.
    """

    returncode: int | None
    stdout: str
    stderr: str
    timed_out: bool
    seconds: float
    traceback: str

    def describe(self) -> str:
        """One sentence for an "observed" text: how it ended, with the traceback's last line."""
        if self.timed_out:
            return f"still running after {self.seconds:.1f} s (stopped)"
        last = self.traceback.strip().splitlines()[-1] if self.traceback.strip() else ""
        return f"exit code {self.returncode} after {self.seconds:.1f} s" + (f" ({last})" if last else "")


def run_program(s: GradingSession, argv: list[str], label: str, *, timeout: float = 30.0,
                env: dict[str, str] | None = None, cwd: Path | None = None) -> ProgramRun:
    """Run ``argv`` to completion (at most ``timeout`` seconds, then stopped) and return what it did.

    Raises nothing for the learner's faults: a program that loops, floods
    output or never exits comes back with ``timed_out`` and capped output.
    """
    proc = s.start_program(argv, label, env=env, cwd=cwd, deadline=timeout + 10.0)
    begin = time.monotonic()
    with s.phase("run"):
        finished = wait_until(lambda: proc.poll() is not None, timeout, interval=0.02)
    seconds = time.monotonic() - begin
    report = proc.stop(sigint_timeout=0.5, sigterm_timeout=1.0)
    return ProgramRun(report.returncode, proc.stdout(), proc.stderr(), not finished, seconds, report.traceback)


def interrupt_after(s: GradingSession, argv: list[str], label: str, seconds: float, *,
                    exit_timeout: float = 3.0, env: dict[str, str] | None = None,
                    cwd: Path | None = None) -> ProgramRun:
    """Run ``argv`` for ``seconds``, press Ctrl+C (SIGINT to its group), wait ``exit_timeout`` s for it to end.

    For scripts that run until stopped (the tutorial's ``minimalist_script.py``,
    ch. 2.4). ``timed_out`` is True when it was still running ``exit_timeout``
    seconds after SIGINT (it was then stopped with SIGTERM/SIGKILL); a script that
    ended before SIGINT comes back with its own exit code and ``seconds`` < ``seconds``.
    """
    proc = s.start_program(argv, label, env=env, cwd=cwd, deadline=seconds + exit_timeout + 10.0)
    begin = time.monotonic()
    with s.phase("run"):
        ended_early = wait_until(lambda: proc.poll() is not None, seconds, interval=0.02)
        if not ended_early:
            try:
                os.killpg(proc.pid, signal.SIGINT)
            except (ProcessLookupError, PermissionError):
                pass
        exited = wait_until(lambda: proc.poll() is not None, exit_timeout, interval=0.01)
    elapsed = time.monotonic() - begin
    report = proc.stop(sigint_timeout=0.1, sigterm_timeout=1.0)
    return ProgramRun(report.returncode, proc.stdout(), proc.stderr(), not exited, elapsed, report.traceback)
