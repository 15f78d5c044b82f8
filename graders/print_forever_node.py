"""Grader for ``print-forever-node`` (seed ch. 12-13; contract in shared/LESSONS.md).

Black-box: watches /rosout for the node's records, never reads its source
(except package.xml, whose rclpy dependency the contract names).
"""

from __future__ import annotations

import re

from course.grading import Check, GradingSession
from course.probes import stamp_seconds, wait_until
from graders._common import process_state, record_rate, record_sigint_exit, require_executable, wait_for_node

PACKAGE = "python_package_with_a_node"
EXECUTABLE = "print_forever_node"
NODE = "print_forever"
PERIOD = 0.5  # seconds, seed ch. 13.3
SAMPLES = 6  # records -> 5 intervals, the minimum LESSONS.md asks for
#: Seconds of observation the contract needs: the first record 0.5 s after start, then 5 intervals.
WINDOW = SAMPLES * PERIOD
LOG = re.compile(r"^Printed (-?\d+) times\.$")
INFO = 20  # rcl_interfaces/msg/Log.INFO

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("depends_rclpy", "package.xml declares the rclpy dependency", 1,
          "add <depend>rclpy</depend> to package.xml (seed ch. 12.1)"),
    Check("executable", "ros2 run finds print_forever_node", 2,
          "add 'print_forever_node = python_package_with_a_node.print_forever_node:main' to console_scripts in setup.py, then colcon build"),
    Check("node_name", "A node named print_forever starts", 2,
          "pass 'print_forever' to super().__init__() in your Node subclass"),
    Check("log_format", "It logs 'Printed N times.' on /rosout", 2,
          "use self.get_logger().info(f'Printed {self.print_count} times.') in the timer callback; print() does not reach /rosout"),
    Check("counts_from_zero", "N counts 0, 1, 2, ...", 2,
          "start the counter at 0 in __init__ and add 1 after each log"),
    Check("rate", "One record every 0.5 s (2 Hz)", 2,
          "create the timer with create_timer(0.5, self.timer_callback)"),
    Check("sigint_exit", "Ctrl+C ends it with exit code 0 and no traceback", 2,
          "in Jazzy rclpy.spin() may raise ExternalShutdownException on Ctrl+C: catch it together with KeyboardInterrupt"),
]


def _check_package_xml(s: GradingSession) -> None:
    from course.build import find_packages  # noqa: PLC0415

    found = find_packages(s.workspace_root / "src").get(PACKAGE)
    if found is None:
        s.record("depends_rclpy", False, f"no package {PACKAGE} in src/", "<depend>rclpy</depend> in package.xml")
        return
    pkg = found[1]
    deps = {d.name for d in (*pkg.exec_depends, *pkg.build_depends)}
    s.record("depends_rclpy", "rclpy" in deps,
             f"package.xml run dependencies: {', '.join(sorted(deps)) or 'none'}",
             "rclpy among them (<depend>rclpy</depend>)")


def grade(s: GradingSession) -> None:
    """Run print_forever_node, read its /rosout records, then Ctrl+C it."""
    _check_package_xml(s)
    path = require_executable(s, "executable", PACKAGE, EXECUTABLE)
    if path is None:
        return
    rosout = s.ros.rosout()
    proc = s.launch(path, EXECUTABLE)
    if not wait_for_node(s, "node_name", proc, NODE):
        if proc.poll() is not None:
            s.skip_remaining(process_state(proc))
            record_sigint_exit(s, "sigint_exit", proc)
            return

    def counted():
        return [r for r in rosout.records(level=INFO) if LOG.match(r.msg)]

    with s.phase("observe"):
        wait_until(lambda: len(counted()) >= SAMPLES, timeout=SAMPLES * PERIOD + 3.0,
                   abort=lambda: proc.poll() is not None)
    records = counted()
    everything = rosout.records()
    if not records:
        texts = [f"[{r.name}] {r.msg}" for r in everything[:3]]
        on_stdout = "Printed 0 times." in proc.stdout()
        observed = ("no /rosout records" if not texts else "records: " + " | ".join(texts))
        if on_stdout:
            observed += "; 'Printed 0 times.' appeared on stdout only (print() instead of the logger?)"
        s.record("log_format", False, observed + f"; {process_state(proc)}", "INFO records 'Printed N times.'")
        s.skip_remaining("no 'Printed N times.' record to judge")
        record_sigint_exit(s, "sigint_exit", proc)
        return
    loggers = sorted({r.name for r in records})
    s.record("log_format", True, f"{len(records)} records like '{records[0].msg}' from {', '.join(loggers)}",
             "INFO records 'Printed N times.'")
    # Judge the busiest logger: a second node of the learner's must not confuse the count.
    main = max(loggers, key=lambda name: sum(r.name == name for r in records))
    mine = [r for r in records if r.name == main]
    counts = [int(LOG.match(r.msg).group(1)) for r in mine]
    shown = ", ".join(map(str, counts[:8])) + (", ..." if len(counts) > 8 else "")
    s.record("counts_from_zero", counts == list(range(len(counts))), f"N = {shown}",
             "N = " + ", ".join(map(str, range(min(len(counts), 8)))) + ", ...")
    record_rate(s, "rate", [stamp_seconds(r.stamp) for r in mine], period=PERIOD, needed=SAMPLES,
                waited=SAMPLES * PERIOD + 3.0, noun="record", source="the records' stamps")
    record_sigint_exit(s, "sigint_exit", proc)
