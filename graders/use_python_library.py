"""Grader for ``use-python-library`` (seed ch. 15; contract in shared/LESSONS.md).

Black-box: runs ``node_that_uses_the_library`` and reads its ``/rosout`` records.
Every 0.5 s the node logs ``sample_function_for_square_of_sum(a,b) returned c.``
(a in [0, 1], b in [1, 2], c == (a+b)**2) and then
``sample_class_with_random_name.get_name() returned NAME.`` (ten random ASCII
letters). Numbers are parsed however the node formats them; c is compared with
(a+b)**2 within the rounding of the printed digits (``ros2course.kit.packaging.SquareLine``).
Only ``package.xml`` is read, for the dependency on the library the contract names.
The node's parameter services are asked once: a timer and ``rclpy.spin()``, not a
``while`` loop (``spins``, ros2course.kit.checks.spins).

Then the node runs once more, in a graph of its own, with a stand-in of the library first on
``PYTHONPATH`` (the same modules as the lesson's library, whose function returns (a+b)**2 +
:data:`WITNESS_OFFSET` and whose ``SampleClass.get_name()`` returns ``Witness`` + the name): a node that
uses the library logs those values (``uses_library``); one that computes c or keeps the name itself, or
reaches the library's sources in ``src/`` with a ``sys.path`` trick, does not.
"""

from __future__ import annotations

from ros2course.kit import LATE_DELIVERY, stamp_seconds, wait_until
from ros2course import kit
from ros2course.kit import Check, Session, checks, params, python_programs
from ros2course.kit.packaging import (
    classify,
    name_lines,
    parse_name_line,
    parse_square_line,
    ros2_run_executable,
    shorten,
    square_lines,
)


PACKAGE = "python_package_that_uses_the_library"
LIBRARY = "python_package_with_a_library"
EXECUTABLE = "node_that_uses_the_library"
NODE = "node_that_uses_the_library"
PERIOD = 0.5  # seconds, seed ch. 15.1
#: Square records read: 11 intervals (LESSONS.md asks for 5 at least); with 12 draws, a b drawn from [1, 3]
#: instead of [1, 2] stays in range in 1 run of 4096 (with 6 it did in 1 of 64: the ranges check let it pass)
SAMPLES = 12
#: Different values each of a and b must take over the records: integer draws take two.
DISTINCT_VALUES = 3
INFO = 20  # rcl_interfaces/msg/Log.INFO
SQUARE_FORMAT = "sample_function_for_square_of_sum(a,b) returned c."
NAME_FORMAT = "sample_class_with_random_name.get_name() returned NAME."

#: Seconds of observation: first record after one period, then SAMPLES - 1 intervals.
WINDOW = SAMPLES * PERIOD
#: What the stand-in library's function adds to (a+b)**2, and what its get_name() puts before the name.
WITNESS_OFFSET = 1000.0
WITNESS_PREFIX = "Witness"
#: The stand-in library: the lesson's public module and its two private ones (seed ch. 14), so a node that
#: imports either way finds them; values no node computes by itself.
WITNESS_FILES = {
    "__init__.py": "",
    "sample_python_library/__init__.py":
        "from python_package_with_a_library.sample_python_library._sample_class import SampleClass\n"
        "from python_package_with_a_library.sample_python_library._sample_function import "
        "sample_function_for_square_of_sum\n__all__ = ['SampleClass', 'sample_function_for_square_of_sum']\n",
    "sample_python_library/_sample_class.py":
        "class SampleClass:\n    def __init__(self, name):\n        self._name = name\n\n"
        f"    def get_name(self):\n        return '{WITNESS_PREFIX}' + self._name\n",
    "sample_python_library/_sample_function.py":
        f"def sample_function_for_square_of_sum(a, b):\n    return (a + b) ** 2 + {WITNESS_OFFSET}\n",
}

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
    checks.spins(),
    Check("uses_library", "c comes from the library's function and the name from SampleClass.get_name()", 2,
          "import them (from python_package_with_a_library.sample_python_library import SampleClass, "
          "sample_function_for_square_of_sum), log c = sample_function_for_square_of_sum(a, b) and "
          "SampleClass(name=...).get_name(); never compute them yourself or add src/ to sys.path",
          needs=("square_log",)),
]


def _numbers_random(s: Session, records: list) -> None:
    """``numbers_random``: the logged a and b take :data:`DISTINCT_VALUES` values or more over the square-of-sum
    records (seed ch. 15.1: two random numbers per tick, a in [0, 1], b in [1, 2]). Uniform draws never repeat
    (printed with two decimals, three of six repeat about once in 10^7); integer draws (random.randint(0, 1))
    take two values, and passed the old test (not the same in every record) in about 15 runs of 16, by luck
    (helper audit of issue 37)."""
    lines = [parse_square_line(r.msg) for r in records]
    wanted = min(DISTINCT_VALUES, len(lines))
    expected = (f"a and b drawn anew at every tick from a continuous range (random.uniform): at least {wanted} "
                f"different values of each in {len(lines)} records")
    if len(lines) < 2:
        s.record("numbers_random", False, f"only {len(lines)} record(s) to compare", expected)
        return
    few = [f"{name} took {len(values)} value(s) ({', '.join(f'{v:g}' for v in sorted(values))})"
           for name, values in (("a", {line.a for line in lines}), ("b", {line.b for line in lines}))
           if len(values) < wanted]
    shown = ", ".join(f"({line.a:g}, {line.b:g})" for line in lines[:4]) + (", ..." if len(lines) > 4 else "")
    s.record("numbers_random", not few,
             (f"{' and '.join(few)} in {len(lines)} records: " if few else "")
             + f"(a, b) = {shown}", expected, fraction=(2 - len(few)) / 2)


def _busiest(records: list) -> str | None:
    """The logger with the most of ``records`` (a second node of the learner's must not confuse the count)."""
    loggers = [r.name for r in records]
    return max(sorted(set(loggers)), key=loggers.count) if loggers else None


def grade(s: Session) -> None:
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
    params.record_spins(s, "spins", started)
    _uses_library(s, path)


def _uses_library(s: Session, path) -> None:
    """Record ``uses_library``: the node run once more, in a graph of its own, with the stand-in library
    (:data:`WITNESS_FILES`) first on PYTHONPATH, logs the stand-in's c (over WITNESS_OFFSET) and get_name()
    (starting with WITNESS_PREFIX): half the points each. ``path``: the node's executable."""
    env = python_programs.stand_in_env(s, "witness-library",
                                       {f"{LIBRARY}/{rel}": text for rel, text in WITNESS_FILES.items()})
    graph = s.new_graph()
    rosout = graph.rosout()
    proc = s.start_program([str(path)], f"{EXECUTABLE}.witness", env=graph.learner_env(env))

    def records(kind: str) -> list:
        return rosout.records(level=INFO, match=lambda text: classify(text) == kind)

    with s.phase("observe"):
        wait_until(lambda: bool(records("square")) and bool(records("name")), 4 * PERIOD + 6.0,
                   abort=lambda: proc.poll() is not None)
    squares = [line for line in map(parse_square_line, (r.msg for r in records("square"))) if line]
    names = [name for name in map(parse_name_line, (r.msg for r in records("name"))) if name]
    proc.stop(sigint_timeout=2.0, sigterm_timeout=2.0)
    expected = (f"with a stand-in of the library first on PYTHONPATH (its function returns (a+b)**2 + "
                f"{WITNESS_OFFSET:g}, its get_name() '{WITNESS_PREFIX}' + the name), the node logs what they return")
    if not squares and not names:
        s.record("uses_library", False, f"no records from the node run against the stand-in library; "
                 f"{kit.process_state(proc)}", expected)
        return
    # the stand-in's c is over WITNESS_OFFSET whatever a and b the node passes; a node's own is (a+b)**2 < 10
    function = bool(squares) and squares[0].c > WITNESS_OFFSET / 2
    named = bool(names) and names[0].startswith(WITNESS_PREFIX)
    seen = []
    if squares:
        line = squares[0]
        seen.append(f"c = {line.c:g} for a = {line.a:g}, b = {line.b:g}" + (
            " (the stand-in's value)" if function else f", not the stand-in's value ({WITNESS_OFFSET:g} more than "
            "(a+b)**2): computed without the library's function, or the library not imported from PYTHONPATH?"))
    else:
        seen.append("no square-of-sum record")
    if names:
        seen.append(f"the name {shorten(names[0])}" + ("" if named else f", without the stand-in's "
                                                              f"'{WITNESS_PREFIX}' (not from SampleClass.get_name()?)"))
    else:
        seen.append("no name record")
    s.record("uses_library", function and named, "; ".join(seen), expected, fraction=(function + named) / 2)

