"""Pieces several graders share: executable lookup, waiting for a node, SIGINT exit."""

from __future__ import annotations

from pathlib import Path

from course.grading import GradingSession
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
                  timeout: float = 10.0, grace: float = 3.0) -> bool:
    """Record ``check_id`` on whether a node called ``node`` appears within ``timeout`` seconds.

    Stops waiting early if the process dies, or ``grace`` seconds after other
    nodes appeared without it (a misnamed node will not rename itself).
    Observed lists the nodes seen.
    """
    import time  # noqa: PLC0415

    first_other: list[float] = []

    def give_up() -> bool:
        if proc.poll() is not None:
            return True
        if not first_other and s.ros.node_names():
            first_other.append(time.monotonic())
        return bool(first_other) and time.monotonic() - first_other[0] > grace

    begin = time.monotonic()
    with s.phase("start"):
        found = s.ros.wait_for_node(node, timeout, abort=give_up)
    waited = time.monotonic() - begin
    seen = ", ".join(s.ros.node_names()) or "none"
    if found:
        return s.record(check_id, True, f"node /{node} is running", f"a node named {node}")
    state = process_state(proc)
    return s.record(check_id, False, f"no node named {node} after {waited:.1f} s; nodes seen: {seen}; {state}",
                    f"a node named {node} (the name passed to super().__init__)")


def record_sigint_exit(s: GradingSession, check_id: str, proc: LearnerProcess, sigint_timeout: float = 3.0) -> bool:
    """Send SIGINT (Ctrl+C) and record ``check_id``: exit code 0, no traceback, within ``sigint_timeout`` s."""
    with s.phase("stop"):
        report = proc.stop(sigint_timeout=sigint_timeout, sigterm_timeout=2.0)
    expected = f"exit code 0 within {sigint_timeout:.0f} s of SIGINT (Ctrl+C), no traceback"
    if report.signal_used is None:
        return s.record(check_id, False, f"the process had already exited (code {report.returncode}) before SIGINT",
                        expected, "the node must keep running until Ctrl+C")
    if report.signal_used != "SIGINT":
        return s.record(check_id, False,
                        f"still running {sigint_timeout:.0f} s after SIGINT; stopped with {report.signal_used}",
                        expected, "don't swallow Ctrl+C in a loop: let rclpy.spin() return and exit main()")
    if report.traceback:
        last = report.traceback.strip().splitlines()[-1]
        return s.record(check_id, False, f"exit code {report.returncode} with a traceback: {last}", expected)
    if report.returncode != 0:
        return s.record(check_id, False, f"exit code {report.returncode} after SIGINT", expected)
    return s.record(check_id, True, f"exit code 0, {report.seconds:.2f} s after SIGINT", expected)
