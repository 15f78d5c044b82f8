"""Pieces several graders share: executable lookup, waiting for a node, SIGINT exit."""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Iterable
from pathlib import Path

from course.grading import GradingSession
from course.probes import RateStats, wait_until
from course.process import LearnerProcess


def require_executable(s: GradingSession, check_id: str, package: str, executable: str,
                       hint: str = "") -> Path | None:
    """Record ``check_id`` on whether ``ros2 run package executable`` would find it.

    On failure every later check is skipped (nothing to run). Returns the path or None.
    """
    path, observed = s.find_executable(package, executable)
    s.record(check_id, path is not None, observed,
             f"ros2 run {package} {executable} finds install/{package}/lib/{package}/{executable}", hint or None)
    if path is None:
        s.skip_remaining(f"there is no {executable} executable to run")
    return path


def process_state(proc: LearnerProcess) -> str:
    """A sentence on whether ``proc`` is still running, with its last traceback line if it died."""
    code = proc.poll()
    if code is None:
        return "the process is still running"
    from course.process import last_traceback  # noqa: PLC0415

    trace = last_traceback(proc.stderr() + "\n" + proc.stdout())
    last = trace.strip().splitlines()[-1] if trace else (proc.stderr().strip().splitlines() or [""])[-1]
    return f"the process exited with code {code}" + (f" ({last})" if last else "")


def wait_for_node(s: GradingSession, check_id: str, proc: LearnerProcess, node: str,
                  timeout: float = 10.0, grace: float = 3.0, before: Iterable[str] = ()) -> bool:
    """Record ``check_id`` on whether a node called ``node`` appears within ``timeout`` seconds.

    Stops waiting early if the process dies, or ``grace`` seconds after other
    nodes appeared without it (a misnamed node will not rename itself).
    Nodes named in ``before`` (those in the graph before ``proc`` started)
    are ignored: a node stopped a moment ago can linger in the graph until
    its DDS participant's lease expires, and must neither end the wait early
    nor be listed as this process's. Observed lists the (new) nodes seen.
    """
    ignored = set(before)
    first_other: list[float] = []

    def new_nodes() -> list[str]:
        return [n for n in s.ros.node_names() if n not in ignored]

    def give_up() -> bool:
        if proc.poll() is not None:
            return True
        if not first_other and new_nodes():
            first_other.append(time.monotonic())
        return bool(first_other) and time.monotonic() - first_other[0] > grace

    begin = time.monotonic()
    with s.phase("start"):
        found = wait_until(lambda: f"/{node}" in new_nodes(), timeout, interval=0.05, abort=give_up)
    waited = time.monotonic() - begin
    if found:
        return s.record(check_id, True, f"node /{node} is running", f"a node named {node}")
    seen = ", ".join(new_nodes()) or "none"
    return s.record(check_id, False, f"no node named {node} after {waited:.1f} s; nodes seen: {seen}; "
                    f"{process_state(proc)}", f"a node named {node} (the name passed to super().__init__)")


#: Tolerance on a mean period, as a fraction (shared/LESSONS.md: rates within ±15 %).
RATE_TOLERANCE = 0.15


def record_rate(s: GradingSession, check_id: str, times: list[float], *, period: float, needed: int,
                waited: float, noun: str, source: str, where: str = "", few_note: str = "") -> bool:
    """Record ``check_id`` on the mean period of ``times`` (seconds, oldest first).

    The formula is ``ros2 topic hz``'s (1 / mean delta, ros2topic/verb/hz.py),
    over stamps taken where the event happened (a message's DDS send stamp,
    a /rosout record's stamp, a request's send stamp), never over arrival
    times: a loaded machine handing the grader two messages at once must not
    change the verdict.

    Args:
        period: expected seconds between events; ±:data:`RATE_TOLERANCE` on the mean.
        needed: events needed (``needed - 1`` intervals, at least 5 per shared/LESSONS.md).
        waited: seconds the grader waited, shown when too few events came.
        noun: what an event is, for the learner ("message", "record", "call").
        source: what ``times`` are, e.g. "the messages' send stamps".
        where: appended to the observed text (e.g. the topic the node really uses).
        few_note: appended only when too few events came (e.g. the process state).
    """
    stats = RateStats.from_times(times)
    expected = (f"{1.0 / period:.2f} Hz: mean period {period:.3f} s ± {RATE_TOLERANCE:.0%}, "
                f"over at least {needed - 1} intervals")
    if stats is None or stats.samples < needed - 1:
        return s.record(check_id, False, f"only {len(times)} {noun}(s) within {waited:.1f} s"
                        + (f" ({stats.describe()})" if stats else "") + where + few_note, expected)
    return s.record(check_id, stats.within(1.0 / period, RATE_TOLERANCE),
                    f"{stats.describe()} (from {source}){where}", expected)


def _rclpy_shutdown_race(trace: str) -> bool:
    """True when ``trace`` ends inside rclpy's executor with a "context is not valid" RCLError."""
    lines = [line for line in trace.strip().splitlines() if line.strip()]
    frames = [line for line in lines if line.lstrip().startswith('File "')]
    last = lines[-1] if lines else ""
    return (bool(frames) and "rclpy/executors.py" in frames[-1] and "RCLError" in last
            and ("context is not valid" in last or "context is invalid" in last))


def record_sigint_exit(s: GradingSession, check_id: str, proc: LearnerProcess, sigint_timeout: float = 3.0) -> bool:
    """Press Ctrl+C (SIGINT) and record ``check_id``: exit code 0, no traceback, within ``sigint_timeout`` s.

    Observed says how long the exit took; fails for an exit code other than 0,
    a traceback, or a process still running (then stopped with SIGTERM /
    SIGKILL). Two allowances for races for races
    inside rclpy (Jazzy 7.1) that are not the learner's doing, measured here
    at about 1 % of SIGINTs each on nodes started the way the engine starts
    them (SIGINT ignored at exec, so only rclpy's handler reacts):

    * a node with nothing to wake it (no timer: a server, a subscriber) can
      miss the shutdown and keep waiting; if it still runs after half the
      timeout it gets a second Ctrl+C, as a user would press it again;
    * ``spin()`` can raise ``RCLError: ... context is not valid`` from inside
      rclpy's executor instead of ``ExternalShutdownException``; that exit
      counts as clean.

    A node that ignores Ctrl+C still fails (it ignores the second one too).
    """
    expected = f"exit code 0 within {sigint_timeout:.0f} s of SIGINT (Ctrl+C), no traceback"
    if proc.poll() is not None:
        report = proc.stop()
        return s.record(check_id, False, f"the process had already exited (code {report.returncode}) before SIGINT",
                        expected, "the node must keep running until Ctrl+C")
    presses = 0
    with s.phase("stop"):
        begin = time.monotonic()
        for wait in (sigint_timeout / 2, sigint_timeout / 2):
            presses += 1
            try:
                os.killpg(proc.pid, signal.SIGINT)
            except (ProcessLookupError, PermissionError):
                break
            if wait_until(lambda: proc.poll() is not None, wait, interval=0.01):
                break
        seconds = time.monotonic() - begin
        exited = proc.poll() is not None
        report = proc.stop(sigint_timeout=0.1, sigterm_timeout=2.0)
    twice = " (after a second Ctrl+C: rclpy missed the first one)" if presses > 1 else ""
    if not exited:
        return s.record(check_id, False,
                        f"still running {sigint_timeout:.0f} s after SIGINT (sent twice); stopped with "
                        f"{report.signal_used or 'SIGKILL'}", expected,
                        "don't swallow Ctrl+C in a loop: let rclpy.spin() return and exit main()")
    if report.traceback:
        if report.returncode != 0 and _rclpy_shutdown_race(report.traceback):
            return s.record(check_id, True, f"exit code {report.returncode}, {seconds:.2f} s after SIGINT{twice}, "
                            "with rclpy's own shutdown race (RCLError inside rclpy.spin: not your code)", expected)
        last = report.traceback.strip().splitlines()[-1]
        return s.record(check_id, False, f"exit code {report.returncode} with a traceback: {last}", expected)
    if report.returncode != 0:
        return s.record(check_id, False, f"exit code {report.returncode} after SIGINT", expected)
    return s.record(check_id, True, f"exit code 0, {seconds:.2f} s after SIGINT{twice}", expected)
