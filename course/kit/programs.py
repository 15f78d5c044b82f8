"""Kit steps for learner programs that are not ROS nodes: scripts, compiled binaries, pip.

They run through :meth:`Session.start_program`: own process group,
capped output, a deadline, nothing left running (the brief's "bad input"
rules apply to every learner program, not only to nodes).
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import re
import signal
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

from ros2course.kit.session_protocol import Session
from ros2course.run.probes import wait_until
from ros2course.run.process import marked_processes, rclpy_shutdown_race

#: What a signal that ended a program usually means, for C++ programs (signal(7)).
_SIGNAL_MEANING = {"SIGABRT": " (abort: an assertion failed or an exception nothing caught)",
                   "SIGSEGV": " (segmentation fault: memory that is not yours was touched)"}
#: Lines of a build's output that say what went wrong (compiler, linker, CMake).
_ERROR_KEYS = ("error", "Error", "undefined reference", "not found", "No such file", "Could not find")
#: Lines of a ``CMake Error``'s indented explanation quoted with it.
_CMAKE_DETAIL_LINES = 3
#: make's own "make[2]: *** ... Error 1" lines: they repeat that something failed, never what.
_MAKE_LINE = re.compile(r"g?make(\[\d+\])?: ")


@dataclasses.dataclass(frozen=True)
class ProgramRun:
    """What a finished (or stopped) learner program did.

    Attributes:
        returncode: exit code (negative: killed by that signal; None: never started).
        stdout, stderr: captured text (capped).
        timed_out: it was still running at the timeout and was stopped.
        seconds: wall time from start to exit or stop.
        traceback: the last Python traceback in its output, "" if none.
        interrupted: Ctrl+C (SIGINT) was sent to it (:func:`interrupt_after`); False when it ended by itself first.
        left_running: processes it started that were still running when it exited (``ros2`` daemons
            excepted: they are meant to outlive the command that spawned them), ``"<pid> <command>"``.
        interrupted_at: seconds after it started when Ctrl+C was pressed (None: never pressed).
    """

    returncode: int | None
    stdout: str
    stderr: str
    timed_out: bool
    seconds: float
    traceback: str
    interrupted: bool = False
    left_running: tuple[str, ...] = ()
    interrupted_at: float | None = None

    def ending(self) -> str:
        """How it ended, in words: ``exit code 1``, ``ended by SIGINT``, ``killed by SIGSEGV (segmentation ...)``.

        Signals are named (signal(7)) instead of the negative code ``subprocess`` reports.
        """
        if self.timed_out:
            return f"still running after {self.seconds:.1f} s (stopped)"
        if self.returncode is None or self.returncode >= 0:
            return f"exit code {self.returncode}"
        try:
            name = signal.Signals(-self.returncode).name
        except ValueError:
            name = f"signal {-self.returncode}"
        return f"ended by {name}" if name == "SIGINT" else f"killed by {name}{_SIGNAL_MEANING.get(name, '')}"

    def exception(self) -> str:
        """The traceback's last line (``ValueError: ...``), "" without one.

        :attr:`traceback` is :func:`ros2course.run.process.last_traceback`: it ends at the exception line.
        """
        return last_line(self.traceback)

    def describe(self) -> str:
        """One sentence for an "observed" text: how it ended, after how long, with the exception it raised."""
        if self.timed_out:
            return self.ending()
        last = self.exception()
        return f"{self.ending()} after {self.seconds:.1f} s" + (f" ({last})" if last else "")

    def left_running_text(self, count: int = 3) -> str:
        """The first ``count`` of :attr:`left_running` as a learner typed them (``ros2 topic hz /chatter``), "; "
        between them: the pid, the interpreter of a Python program and the folders of the program are left out."""
        names = []
        for entry in self.left_running[:count]:
            words = entry.split(" ")[1:]  # "<pid> <command line>"
            if len(words) > 1 and Path(words[0]).name.startswith("python"):
                words = words[1:]
            if words:
                words[0] = Path(words[0]).name
            names.append(" ".join(words)[:80])
        return "; ".join(names)


def last_line(text: str) -> str:
    """The last non-blank line of ``text``, stripped ("" if none)."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else ""


def compile_errors(run: ProgramRun, *, paths: Mapping[str, str] | None = None, limit: int = 4) -> str:
    """The lines of a compiler / linker / CMake run that say what went wrong, for feedback.

    A ``CMake Error`` line comes with its indented explanation (CMake prints it on
    the next lines); make's own ``Error 1/2`` lines are left out. Without any such
    line: how the run ended and its last line of output.

    Args:
        paths: text to shorten in the excerpt, e.g. ``{"/tmp/x/scratch": "<grader>"}`` (grader folders).
        limit: most lines kept.
    """
    if run.timed_out:
        return run.describe()
    lines = [line.rstrip() for line in (run.stderr + "\n" + run.stdout).splitlines() if line.strip()]
    picked: list[str] = []
    consumed = -1  # the last line already quoted as a CMake Error's explanation
    for i, line in enumerate(lines):
        if i <= consumed or _MAKE_LINE.match(line) or line.startswith("-- Configuring incomplete") \
                or not any(key in line for key in _ERROR_KEYS):
            continue
        detail = []
        if line.startswith("CMake Error"):
            for more in lines[i + 1:i + 1 + _CMAKE_DETAIL_LINES]:  # CMake indents the explanation under the line
                if not more.startswith(" "):
                    break
                detail.append(more.strip())
            consumed = i + len(detail)
        picked.append(" ".join([line.strip(), *detail]))
        if len(picked) >= limit:
            break
    text = "\n".join(picked) or (f"{run.ending()}" + (f", last output: {last_line(run.stderr + run.stdout)}"
                                                       if (run.stderr + run.stdout).strip() else ""))
    for path, short in (paths or {}).items():
        text = text.replace(path, short)
    return text


#: Seconds a program's children get to end after it exited before they count as left running: a child it
#: signalled as it ended (``kill $!; exit``) is still exiting then, one it never stopped (``cmd &``) is not.
LEFT_GRACE = 1.0


def run_program(s: Session, argv: list[str], label: str, *, timeout: float = 30.0,
                env: dict[str, str] | None = None, cwd: Path | None = None, stdin_open: bool = False) -> ProgramRun:
    """Run ``argv`` to completion (at most ``timeout`` seconds, then stopped) and return what it did.

    Raises nothing for the learner's faults: a program that loops, floods
    output or never exits comes back with ``timed_out`` and capped output. ``stdin_open``: its stdin is a pipe
    nobody writes to, so a program that asks something waits (and times out) as in a terminal nobody types
    into (:meth:`~ros2course.grade.session.GradingSession.start_program`).
    """
    proc = s.start_program(argv, label, env=env, cwd=cwd, deadline=timeout + 10.0, stdin_open=stdin_open)
    begin = time.monotonic()
    with s.phase("run"):
        finished = wait_until(lambda: proc.poll() is not None, timeout, interval=0.02)
    seconds = time.monotonic() - begin
    if finished:  # a child it killed as it ended (`kill $!` then exit) is given LEFT_GRACE s to be gone
        wait_until(lambda: not _children(tuple(marked_processes(proc.marker))), LEFT_GRACE, interval=0.05)
    report = proc.stop(sigint_timeout=0.5, sigterm_timeout=1.0)
    # what it left running when it ended by itself (a `cmd &` never waited for), ros2 daemons aside: stopped here
    # with the run, and named so that kit.scripts.ended can fail on it
    return ProgramRun(report.returncode, proc.stdout(), proc.stderr(), not finished, seconds, report.traceback,
                      left_running=_children(report.left_running))


def interrupt_after(s: Session, argv: list[str], label: str, seconds: float, *,
                    exit_timeout: float = 3.0, env: dict[str, str] | None = None, cwd: Path | None = None,
                    wait_for: str | Callable[[], bool] | None = None, first_timeout: float = 10.0) -> ProgramRun:
    """Run ``argv`` for ``seconds``, press Ctrl+C (SIGINT to its group), wait ``exit_timeout`` s for it to end.

    For scripts that run until stopped (the tutorial's ``minimalist_script.py``,
    ch. 2.4). ``timed_out`` is True when it was still running ``exit_timeout``
    seconds after SIGINT (it was then stopped with SIGTERM/SIGKILL); a script that
    ended before SIGINT comes back with its own exit code, ``interrupted`` False.

    Args:
        seconds: how long it runs before Ctrl+C.
        wait_for: when given, the ``seconds`` count from the moment this text first
            appears on its stdout, or this predicate first returns True (e.g. "every node
            the script starts is in the graph"), waiting at most ``first_timeout`` s for
            it; if it never comes, Ctrl+C comes then. A count of lines over the window
            then does not depend on the interpreter's start-up time on a loaded machine,
            and Ctrl+C never lands in a Python node still importing rclpy (a
            KeyboardInterrupt there is a traceback no ``try`` in ``main`` can catch).

    Raises:
        OSError: the program cannot be started (e.g. not executable).
    """
    waited = first_timeout if wait_for is not None else 0.0
    proc = s.start_program(argv, label, env=env, cwd=cwd, deadline=waited + seconds + exit_timeout + 10.0)
    begin = time.monotonic()
    with s.phase("run"):
        window = seconds
        if wait_for is not None:
            ready = wait_for if callable(wait_for) else lambda: wait_for in proc.stdout()
            wait_until(lambda: proc.poll() is not None or ready(), first_timeout)
            window = seconds if ready() else 0.0
        ended_early = wait_until(lambda: proc.poll() is not None, window, interval=0.02)
        interrupted_at = None
        if not ended_early:
            interrupted_at = time.monotonic() - begin
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(proc.pid, signal.SIGINT)
        exited = ended_early or wait_until(lambda: proc.poll() is not None, exit_timeout, interval=0.01)
    elapsed = time.monotonic() - begin
    report = proc.stop(sigint_timeout=0.1, sigterm_timeout=1.0)
    return ProgramRun(report.returncode, proc.stdout(), proc.stderr(), not exited, elapsed, report.traceback,
                      interrupted=not ended_early, left_running=_children(report.left_running),
                      interrupted_at=interrupted_at)


#: The command line of a ``ros2`` daemon (ros2cli.daemon.daemonize), which outlives the command that spawned it.
_DAEMON = "ros2cli.daemon.daemonize"


def _children(left: tuple[str, ...]) -> tuple[str, ...]:
    """What a program left running, ``ros2`` daemons excepted."""
    return tuple(p for p in left if _DAEMON not in p)


def judge_interrupted_run(s: Session, check_id: str, run: ProgramRun, exit_timeout: float = 3.0) -> bool:
    """Record ``check_id`` on a run that :func:`interrupt_after` (or ``scripts.run_script``) ended with Ctrl+C:
    exit code 0, no traceback, nothing it started still running.

    Graders call it as :func:`ros2course.kit.nodes.sigint_exit` (the kit's one
    Ctrl+C step), which hands a :class:`ProgramRun` here. The rule of the
    tutorial's scripts (ch. 2.4: ``except KeyboardInterrupt``) and nodes (ch. 12):
    Ctrl+C is the normal way to stop them, not an error. A program that ended by
    itself before Ctrl+C fails: it was never stopped.

    A script whose nodes run inside it (``ros2 run``/``ros2 launch`` in bash) that exits 0 with nothing left
    running, but printed rclpy's own Ctrl+C race from one of its nodes
    (:func:`~ros2course.run.process.rclpy_shutdown_race`: an error raised inside rclpy itself), passes: the
    script cannot be run again without its nodes' first run, so that exit counts as clean, as
    :func:`~ros2course.kit.nodes.sigint_exit` counts it for a node it cannot start again (CI of stop 54: the
    launch-and-run reference lost its Ctrl+C check once through ``grade``).
    """
    race = (run.interrupted and not run.timed_out and run.returncode == 0 and not run.left_running
            and bool(run.traceback) and rclpy_shutdown_race(run.traceback))
    if not run.interrupted:
        observed = f"it had already ended by itself ({run.describe()}) before Ctrl+C"
    elif run.timed_out:
        observed = f"still running {exit_timeout:.0f} s after Ctrl+C (stopped)"
    elif race:
        observed = (f"{run.ending()}; one of its nodes printed rclpy's own shutdown race (an error raised inside "
                    "rclpy itself when Ctrl+C lands as it works: not your code)")
    elif run.traceback:
        observed = f"{run.ending()} with a traceback: {run.exception()}"
    elif run.left_running:
        observed = (f"{run.ending()}, but while {len(run.left_running)} process(es) it started were still "
                    f"stopping ({run.left_running_text()})")
    else:
        observed = f"{run.ending()}, no traceback"
    return s.record(check_id, race or (run.interrupted and not run.timed_out and run.returncode == 0
                                       and not run.traceback and not run.left_running),
                    observed, f"exit code 0 within {exit_timeout:.0f} s of SIGINT (Ctrl+C), no traceback, "
                    "after everything it started has stopped")


def verdict_test(s: Session, check_id: str, argv: list[str], label: str, *, expected: str,
                 explain: Sequence[Mapping] = (), cwd: Path | None = None, timeout: float = 10.0) -> bool:
    """Run a course test program that prints ``PASS <what it saw>`` or ``FAIL <what it saw>``; record ``check_id``.

    For harnesses compiled with the learner's code (one process per test, so an abort
    ends only that test). A run that ends without a verdict line fails with how it
    ended (signals named) and its last stderr line.

    Args:
        explain: feedback for known mistakes, each ``{"when": [text...], "unless": [text...], "note": str,
            "hint": str}`` matched on the verdict line and stderr; the first match adds ``note`` to the
            observed text and its ``hint`` replaces the check's.
    """
    run = run_program(s, argv, label, timeout=timeout, cwd=cwd)
    verdicts = [line for line in run.stdout.splitlines() if line.startswith(("PASS ", "FAIL "))]
    seen = (verdicts[-1] if verdicts else "") + "\n" + run.stderr
    known = next((e for e in explain if all(w in seen for w in e.get("when", ()))
                  and not any(u in seen for u in e.get("unless", ()))), {})
    if verdicts:
        observed = verdicts[-1][5:]
    else:
        observed = f"the test program ended before giving a verdict: {run.ending()}"
        if not known.get("note") and last_line(run.stderr):
            observed += f"; stderr: {last_line(run.stderr)[:200]!r}"
    if known.get("note"):
        observed += f"; {known['note']}"
    return s.record(check_id, bool(verdicts) and verdicts[-1].startswith("PASS "), observed, expected,
                    hint=known.get("hint"))


def printed_lines(s: Session, check_id: str, run: ProgramRun, line: str, how: str) -> int:
    """Record ``check_id``: the program printed lines that read exactly ``line``; return how many.

    Args:
        how: the command as the learner runs it (e.g. ``./minimalist_script.py``), for feedback.

    The observed text quotes up to three other lines it printed and, when it printed
    none of ``line``, its traceback's or stderr's last line.
    """
    lines = [text.strip() for text in run.stdout.splitlines() if text.strip()]
    count, others = lines.count(line), sorted(set(lines) - {line})
    observed = f"ran {how}: {count} {line!r} line(s)" + (
        f", other output: {', '.join(repr(o) for o in others[:3])}" if others else "")
    if not count and (run.traceback or run.stderr.strip()):
        observed += f"; it crashed: {run.exception()}" if run.traceback else f"; stderr: {last_line(run.stderr)!r}"
    s.record(check_id, count > 0, observed, f"lines that read exactly {line!r} on stdout")
    return count
