"""Grader for ``print-forever-node`` (seed ch. 12-13; contract in shared/LESSONS.md).

Black-box: watches /rosout for the node's records, never reads its source
(except package.xml, whose rclpy dependency the contract names), and asks the
node's parameter services once (``spins``: a node that never spins, a ``while``
loop instead of a timer, cannot answer; :func:`ros2course.kit.params.record_spins`, used by the
use-python-library and publisher-subscriber graders too).
"""

from __future__ import annotations

import re
from collections.abc import Callable

from ros2course.kit import LATE_DELIVERY, stamp_seconds, wait_until
from ros2course import kit
from ros2course.kit import Check, Session, checks, params

PACKAGE = "python_package_with_a_node"
EXECUTABLE = "print_forever_node"
NODE = "print_forever"
PERIOD = 0.5  # seconds, seed ch. 13.3
SAMPLES = 6  # records -> 5 intervals, the minimum LESSONS.md asks for
#: Seconds of observation the contract needs: the first record 0.5 s after start, then 5 intervals.
WINDOW = SAMPLES * PERIOD
LOG = re.compile(r"^Printed (-?\d+) times\.$")
INFO = 20  # rcl_interfaces/msg/Log.INFO



def make_checks(client_library: str = "rclpy", package: str = PACKAGE, node: str = NODE) -> list[Check]:
    """The print-forever checks for a node in ``package`` named ``node`` written with ``client_library``.

    The same black-box checks grade the Python node (``print-forever-node``) and
    its C++ twin (``cpp-node``, graders/cpp_node.py; shared/LESSONS.md).
    """
    python = client_library == "rclpy"
    return [
        Check("build", "The package builds with colcon", 1),
        Check("depends_rclpy" if python else "depends_client", f"package.xml declares the {client_library} dependency",
              1, f"add <depend>{client_library}</depend> to package.xml"
              + (" (seed ch. 12.1)" if python else " (seed ch. 25)")),
        *checks.started("", package, EXECUTABLE, node, points=2, client_library=client_library,
                        executable_hint=None if python else
                        checks.cmake_executable_hint(EXECUTABLE, "src/print_forever_node.cpp")),
        Check("log_format", "It logs 'Printed N times.' on /rosout", 2, needs=("executable",), hint=
              "use self.get_logger().info(f'Printed {self.print_count} times.') in the timer callback; "
              "print() does not reach /rosout" if python else
              "use RCLCPP_INFO(get_logger(), \"Printed %d times.\", count_) in the timer callback; "
              "std::cout does not reach /rosout"),
        Check("counts_from_zero", "N counts 0, 1, 2, ...", 2, needs=("log_format",), hint=
              "start the counter at 0 in __init__ and add 1 after each log" if python else
              "start the counter at 0 in the constructor and add 1 after each log"),
        Check("rate", "One record every 0.5 s (2 Hz)", 2, needs=("log_format",), hint=
              "create the timer with create_timer(0.5, self.timer_callback)" if python else
              "create the timer with create_wall_timer(500ms, ...)"),
        Check("sigint_exit", "Ctrl+C ends it with exit code 0 and no traceback", 2, needs=("executable",), hint=
              "in Jazzy rclpy.spin() may raise ExternalShutdownException on Ctrl+C: catch it together with "
              "KeyboardInterrupt" if python else
              "let rclcpp::spin return on Ctrl+C, then call rclcpp::shutdown() and return 0"),
    ]


CHECKS = [*make_checks(), checks.spins()]


def grade(s: Session) -> None:
    """Run print_forever_node, read its /rosout records, ask its parameter services, then Ctrl+C it."""
    # asked while the records come in (the node answers as soon as it spins): no time added after the window
    grade_node(s, PACKAGE, NODE, "rclpy", while_waiting=lambda started: params.record_spins(s, "spins", started))


def grade_node(s: Session, package: str, node: str, client_library: str, aliases: tuple[str, ...] = (),
               while_waiting: Callable[[kit.StartedNode], object] | None = None) -> kit.StartedNode:
    """The print-forever checks (:func:`make_checks`) of ``package``'s ``print_forever_node`` named ``node``
    (or one of ``aliases``, :func:`ros2course.kit.nodes.wait_for_node`).

    Black-box: the node's /rosout records and exit; the language only shows in
    the ``package.xml`` dependency checked (``rclpy`` or ``rclcpp``). Returns the
    started node, still running (the engine stops it, Ctrl+C check included).
    ``while_waiting(started)``, when given, runs once the node is started, before the
    records are waited for (their subscription keeps collecting meanwhile).
    """
    kit.depends(s, "depends_rclpy" if client_library == "rclpy" else "depends_client", package, (client_library,))
    path = kit.executable(s, "executable", package, EXECUTABLE)
    # a misnamed node is still graded on its records (need_node=False); started first, so it boots while
    # the grader's own participant opens: /rosout is transient local, its first records are replayed
    started = kit.start_node(s, "node_name", path, node, sigint_check="sigint_exit", need_node=False, aliases=aliases)
    rosout = s.ros.rosout()
    if while_waiting is not None:
        while_waiting(started)

    def counted():
        return [r for r in rosout.records(level=INFO) if LOG.match(r.msg)]

    waited = SAMPLES * PERIOD + 3.0 + LATE_DELIVERY
    with s.phase("observe"):
        wait_until(lambda: len(counted()) >= SAMPLES, timeout=waited, abort=started.ended)
    records = counted()
    if not records:
        texts = [f"[{r.name}] {r.msg}" for r in rosout.records()[:3]]
        observed = ("no /rosout records" if not texts else "records: " + " | ".join(texts))
        if "Printed 0 times." in started.proc.stdout():
            instead = "print()" if client_library == "rclpy" else "std::cout"
            observed += f"; 'Printed 0 times.' appeared on stdout only ({instead} instead of the logger?)"
        s.record("log_format", False, f"{observed}; {kit.process_state(started.proc)}",
                 "INFO records 'Printed N times.'")
        return started
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
    kit.rate(s, "rate", [stamp_seconds(r.stamp) for r in mine], period=PERIOD, needed=SAMPLES,
             waited=waited, noun="record", source="the records' stamps")
    return started
