"""Grader for ``use-python-library`` (seed ch. 15; contract in shared/LESSONS.md).

Black-box: runs ``node_that_uses_the_library`` and reads its ``/rosout`` records.
Every 0.5 s the node logs ``sample_function_for_square_of_sum(a,b) returned c.``
(a in [0, 1], b in [1, 2], c == (a+b)**2) and then
``sample_class_with_random_name.get_name() returned NAME.`` (ten random ASCII
letters). Numbers are parsed however the node formats them; c is compared with
(a+b)**2 within the rounding of the printed digits (``ros2course.kit.packaging.SquareLine``).
Only ``package.xml`` is read, for the dependency on the library the contract names.
The node's parameter services are asked once: a timer and ``rclpy.spin()``, not a
``while`` loop (``spins``, graders/print_forever_node.py).
"""

from __future__ import annotations

from ros2course.kit import LATE_DELIVERY, stamp_seconds, wait_until
from ros2course import kit
from ros2course.kit import Check, GradingSession, checks
from ros2course.kit.packaging import (
    classify,
    name_lines,
    parse_square_line,
    ros2_run_executable,
    shorten,
    square_lines,
)

from .print_forever_node import record_spins, spins_check

PACKAGE = "python_package_that_uses_the_library"
LIBRARY = "python_package_with_a_library"
EXECUTABLE = "node_that_uses_the_library"
NODE = "node_that_uses_the_library"
PERIOD = 0.5  # seconds, seed ch. 15.1
SAMPLES = 6  # square records -> 5 intervals, the minimum LESSONS.md asks for
INFO = 20  # rcl_interfaces/msg/Log.INFO
SQUARE_FORMAT = "sample_function_for_square_of_sum(a,b) returned c."
NAME_FORMAT = "sample_class_with_random_name.get_name() returned NAME."

#: Seconds of observation the contract needs: first record after one period, then 5 intervals.
WINDOW = SAMPLES * PERIOD

CHECKS = [
    Check("build", "The package and the library build with colcon", 1),
    Check("depends_library", "package.xml depends on python_package_with_a_library", 1,
          "add <depend>python_package_with_a_library</depend> to package.xml: colcon then builds the library "
          "first, and ros2 run finds it installed"),
    *checks.started("", "python_package_that_uses_the_library", "node_that_uses_the_library",
                    "node_that_uses_the_library", points=2,
                    node_hint="pass 'node_that_uses_the_library' to super().__init__(); if it crashes, read the "
                    "traceback: a ModuleNotFoundError means the library is not built/installed or not sourced"),
    Check("square_log", f"It logs '{SQUARE_FORMAT}' on /rosout", 2,
          "self.get_logger().info(f'sample_function_for_square_of_sum({a},{b}) returned {c}.') in the timer "
          "callback; print() does not reach /rosout", needs=("executable",)),
    Check("ranges", "a is in [0, 1] and b in [1, 2]", 1, "a = random.uniform(0, 1), b = random.uniform(1, 2)",
          needs=("square_log",)),
    Check("numbers_random", "a and b are new random numbers on every tick", 1,
          "draw a = random.uniform(0, 1) and b = random.uniform(1, 2) inside the timer callback, not once in __init__ "
          "or as constants", needs=("square_log",)),
    Check("square_values", "c is (a + b)**2, computed by the library", 2,
          "c = sample_function_for_square_of_sum(a, b), with the same a and b you log", needs=("square_log",)),
    Check("name_log", f"It logs '{NAME_FORMAT}' with ten ASCII letters", 2,
          "''.join(random.choice(string.ascii_letters) for _ in range(10)), passed to SampleClass(name=...), "
          "then log get_name()", needs=("executable",)),
    Check("pairs", "Each square-of-sum record is followed by a name record", 1,
          "log the two lines one after the other in the same timer callback", needs=("square_log",)),
    Check("names_differ", "The name is different each time", 1,
          "make a new random name (and a new SampleClass) inside the timer callback, not once in __init__",
          needs=("executable",)),
    Check("rate", "One pair of records every 0.5 s (2 Hz)", 2,
          "create the timer with create_timer(0.5, self.timer_callback)", needs=("square_log",)),
    Check("sigint_exit", "Ctrl+C ends it with exit code 0 and no traceback", 2,
          "in Jazzy rclpy.spin() may raise ExternalShutdownException on Ctrl+C: catch it together with "
          "KeyboardInterrupt", needs=("executable",)),
    spins_check(),
]


def _numbers_random(s: GradingSession, records: list) -> None:
    """``numbers_random``: the logged a and b are not the same in every square-of-sum record (seed ch. 15.1:
    two random numbers per tick). Two uniform draws printed with Python's default repr never repeat."""
    lines = [parse_square_line(r.msg) for r in records]
    expected = "a and b change from one record to the next (random.uniform in the timer callback)"
    if len(lines) < 2:
        s.record("numbers_random", False, f"only {len(lines)} record(s) to compare", expected)
        return
    constant = [name for name, values in (("a", {line.a for line in lines}), ("b", {line.b for line in lines}))
                if len(values) == 1]
    shown = ", ".join(f"({line.a:g}, {line.b:g})" for line in lines[:4]) + (", ..." if len(lines) > 4 else "")
    s.record("numbers_random", not constant,
             (f"{' and '.join(constant)} the same in all {len(lines)} records: " if constant else "")
             + f"(a, b) = {shown}", expected, fraction=(2 - len(constant)) / 2)


def _busiest(records: list) -> str | None:
    """The logger with the most of ``records`` (a second node of the learner's must not confuse the count)."""
    loggers = [r.name for r in records]
    return max(sorted(set(loggers)), key=loggers.count) if loggers else None


def grade(s: GradingSession) -> None:
    """Run the node, read its /rosout records, judge them, then Ctrl+C it."""
    kit.depends(s, "depends_library", PACKAGE, (LIBRARY,))
    path = ros2_run_executable(s, "executable", PACKAGE, EXECUTABLE)
    rosout = s.ros.rosout()
    # a misnamed node is still graded on its records (need_node=False)
    started = kit.start_node(s, "node_name", path, NODE, sigint_check="sigint_exit", need_node=False)

    def of_kind(kind: str) -> list:
        return rosout.records(level=INFO, match=lambda text: classify(text) == kind)

    def enough() -> bool:
        # SAMPLES square records, and the name record that follows the last one (or one more tick);
        # a node logging names but no square lines will not start now: stop waiting
        count, names = len(of_kind("square")), len(of_kind("name"))
        return (count >= SAMPLES and (names >= SAMPLES or count > SAMPLES)) or (count == 0 and names >= SAMPLES)

    waited = SAMPLES * PERIOD + 3.0 + LATE_DELIVERY
    with s.phase("observe"):
        wait_until(enough, timeout=waited, abort=started.ended)
    squares = of_kind("square")
    main = _busiest(squares or of_kind("name"))  # without square lines, the name lines are still judged
    mine = [r for r in squares if r.name == main]
    if mine:
        s.record("square_log", True, f"{len(mine)} records like '{shorten(mine[0].msg)}' from {main}",
                 f"INFO records '{SQUARE_FORMAT}'")
    else:
        texts = [f"[{r.name}] {shorten(r.msg)}" for r in rosout.records()[:3]]
        observed = "no /rosout records" if not texts else "records: " + " | ".join(texts)
        if "sample_function_for_square_of_sum(" in started.proc.stdout():
            observed += "; the line appeared on stdout only (print() instead of the logger?)"
        s.record("square_log", False, f"{observed}; {kit.process_state(started.proc)}",
                 f"INFO records '{SQUARE_FORMAT}'")
    square_lines(s, "ranges", "square_values", mine)
    _numbers_random(s, mine)
    # this node's records of either kind, in order (other lines it may log are ignored)
    ordered = [r for r in rosout.records(node=main, level=INFO) if classify(r.msg) != "other"] if main else []
    name_lines(s, "name_log", "pairs", "names_differ", ordered, max_gap=PERIOD / 2)
    kit.rate(s, "rate", [stamp_seconds(r.stamp) for r in mine], period=PERIOD, needed=SAMPLES, waited=waited,
             noun="record", source="the records' stamps")
    record_spins(s, "spins", started)
