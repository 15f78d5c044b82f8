"""Grader for ``python-node-template`` (seed ch. 8-11; contract in shared/LESSONS.md).

Runs ``sample_python_node`` the way ``ros2 run`` does (found through the ament
index, ``lib/<package>/<executable>``, with the workspace sourced) and judges
what it prints and how it exits. The template node uses no ROS API, so no ROS
graph is started.
"""

from __future__ import annotations

from ros2course.kit import wait_until
from ros2course.kit import Check, Session
from ros2course.kit.packaging import ros2_run_executable, run_installed_python

PACKAGE = "python_package_with_a_node"
EXECUTABLE = "sample_python_node"
GREETING = "Hi from python_package_with_a_node."  # seed ch. 10 (template output)
EXIT_TIMEOUT = 10.0  # seconds: the program prints one line; a slow start of the interpreter fits easily

#: The template executable prints once and exits: nothing to watch over time.
WINDOW = 0.0

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("executable", "ros2 run finds sample_python_node", 2,
          "register 'sample_python_node = python_package_with_a_node.sample_python_node:main' in console_scripts "
          "(setup.py), keep setup.cfg's install_scripts=$base/lib/python_package_with_a_node, then colcon build"),
    Check("greeting", "It prints 'Hi from python_package_with_a_node.' once", 3,
          "main() prints exactly: Hi from python_package_with_a_node. (once: ros2 run calls main() itself, so "
          "nothing at the module's top level calls it again)", needs=("executable",)),
    Check("exit_code", "It ends by itself with exit code 0 and no traceback", 2,
          "main() should print and return; no loop, no sys.exit() with a non-zero code", needs=("executable",)),
    Check("greeting_in_main", "main() prints the greeting; importing the module prints nothing", 1,
          "put the print inside main(): a print at the module's top level runs when ros2 run imports the "
          "module, and main() then does nothing", needs=("executable",)),
]

#: Run with the workspace's Python: import the node's module, then call main(), each with stdout captured.
_IMPORT_THEN_MAIN = """
import contextlib, io, json, sys
out = {}
buffer = io.StringIO()
try:
    with contextlib.redirect_stdout(buffer):
        import python_package_with_a_node.sample_python_node as module
    out["import"] = buffer.getvalue()
    buffer = io.StringIO()
    try:
        with contextlib.redirect_stdout(buffer):
            module.main()
    except SystemExit as exc:  # sys.exit(0) at the end of main() is a clean end, as under ros2 run
        if exc.code not in (None, 0):
            raise
    out["main"] = buffer.getvalue()
except BaseException as exc:
    out["error"] = f"{type(exc).__name__}: {exc}"
with open(sys.argv[1], "w", encoding="utf-8") as handle:
    json.dump(out, handle)
"""


def _lines(text: str, limit: int = 3) -> str:
    """The first ``limit`` non-blank lines of ``text``, quoted and joined with `` | `` ("nothing" if none)."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    shown = " | ".join(repr(line) for line in lines[:limit])
    return shown + (f" (+{len(lines) - limit} more lines)" if len(lines) > limit else "") if lines else "nothing"


def grade(s: Session) -> None:
    """Run the executable once, wait for it to end, judge its stdout and exit code."""
    path = ros2_run_executable(s, "executable", PACKAGE, EXECUTABLE)
    # not a ROS node (the template uses no ROS API): a program, with the workspace sourced as 'ros2 run' has it
    proc = s.start_program([str(path)], EXECUTABLE, env=s.overlay(), deadline=EXIT_TIMEOUT + 20.0)
    try:
        with s.phase("run"):
            wait_until(lambda: proc.poll() is not None, timeout=EXIT_TIMEOUT, interval=0.02)
        ended_alone = proc.poll() is not None
        with s.phase("stop"):
            report = proc.stop(sigint_timeout=2.0, sigterm_timeout=2.0)
    finally:
        proc.stop(sigint_timeout=1.0, sigterm_timeout=1.0)
    out = proc.stdout()
    printed = [line.strip() for line in out.splitlines()]
    # the lesson shows the whole output: one line, the greeting, then the program ends (seed ch. 10)
    ok = [line for line in printed if line] == [GREETING]
    observed = f"stdout: {_lines(out)}"
    if printed.count(GREETING) > 1:
        observed += f" (the greeting {printed.count(GREETING)} times: is main() also called when the module is imported?)"
    if not ok and GREETING not in printed and GREETING.lower() in [line.lower().rstrip(".") + "." for line in printed]:
        observed += " (close: check capitals and the final period)"
    if not ok and proc.stderr().strip() and not report.traceback:
        observed += f"; stderr: {_lines(proc.stderr())}"
    if not ok and report.traceback:
        observed += f"; it crashed: {report.traceback.strip().splitlines()[-1]}"
    if printed.count(GREETING) == 1 and not ok:
        observed += " (other lines besides the greeting)"
    s.record("greeting", ok, observed, f"one line {GREETING!r} on stdout, and nothing else")
    _greeting_in_main(s)
    expected = f"exit code 0 within {EXIT_TIMEOUT:.0f} s, no traceback"
    if not ended_alone:
        s.record("exit_code", False, f"still running after {EXIT_TIMEOUT:.0f} s (stopped with {report.signal_used})",
                 expected, "the template node prints once and returns from main(); it must not wait or loop")
    elif report.traceback:
        s.record("exit_code", False, f"exit code {report.returncode} with a traceback: "
                 f"{report.traceback.strip().splitlines()[-1]}", expected)
    else:
        s.record("exit_code", report.returncode == 0, f"exit code {report.returncode}", expected)


def _greeting_in_main(s: Session) -> None:
    """``greeting_in_main``: importing the installed module prints nothing, calling its main() prints the greeting
    (helper audit of issue 37: a print at the module's top level and an empty main() printed the same one line
    through ros2 run)."""
    found, problem = run_installed_python(s, _IMPORT_THEN_MAIN)
    expected = f"import python_package_with_a_node.sample_python_node prints nothing; main() prints {GREETING!r}"
    if problem or "error" in found:
        s.record("greeting_in_main", False, problem or found["error"], expected)
        return
    at_import, in_main = found.get("import", ""), found.get("main", "")
    s.record("greeting_in_main", not at_import.strip() and GREETING in in_main,
             f"the import printed {_lines(at_import)}; main() printed {_lines(in_main)}", expected)
