"""Grader for ``use-python-library`` (seed ch. 15; contract in shared/LESSONS.md).

Black-box: runs ``node_that_uses_the_library`` and reads its ``/rosout`` records.
Every 0.5 s the node logs ``sample_function_for_square_of_sum(a,b) returned c.``
(a in [0, 1], b in [1, 2], c == (a+b)**2) and then
``sample_class_with_random_name.get_name() returned NAME.`` (ten random ASCII
letters). Numbers are parsed however the node formats them; c is compared with
(a+b)**2 within the rounding of the printed digits (``graders.kit.packaging.SquareLine``).
Only ``package.xml`` is read, for the dependency on the library the contract names.
"""

from __future__ import annotations

from course.grading import Check, GradingSession
from course.probes import LATE_DELIVERY, stamp_seconds, wait_until
from graders._common import process_state, record_rate, record_sigint_exit, wait_for_node
from graders.kit.packaging import (
    classify,
    is_ten_letters,
    parse_name_line,
    parse_square_line,
    require_ros2_run_executable,
    run_dependencies,
    source_package,
    unpaired,
)

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
    Check("executable", "ros2 run finds node_that_uses_the_library", 2,
          "register 'node_that_uses_the_library = python_package_that_uses_the_library.node_that_uses_the_library:main' "
          "in console_scripts (setup.py), then colcon build"),
    Check("node_name", "A node named node_that_uses_the_library starts", 2,
          "pass 'node_that_uses_the_library' to super().__init__(); if it crashes, read the traceback: "
          "a ModuleNotFoundError means the library is not built/installed or not sourced"),
    Check("square_log", f"It logs '{SQUARE_FORMAT}' on /rosout", 2,
          "self.get_logger().info(f'sample_function_for_square_of_sum({a},{b}) returned {c}.') in the timer "
          "callback; print() does not reach /rosout"),
    Check("ranges", "a is in [0, 1] and b in [1, 2]", 1, "a = random.uniform(0, 1), b = random.uniform(1, 2)"),
    Check("square_values", "c is (a + b)**2, computed by the library", 2,
          "c = sample_function_for_square_of_sum(a, b), with the same a and b you log"),
    Check("name_log", f"It logs '{NAME_FORMAT}' with ten ASCII letters", 2,
          "''.join(random.choice(string.ascii_letters) for _ in range(10)), passed to SampleClass(name=...), "
          "then log get_name()"),
    Check("pairs", "Each square-of-sum record is followed by a name record", 1,
          "log the two lines one after the other in the same timer callback"),
    Check("names_differ", "The name is different each time", 1,
          "make a new random name (and a new SampleClass) inside the timer callback, not once in __init__"),
    Check("rate", "One pair of records every 0.5 s (2 Hz)", 2,
          "create the timer with create_timer(0.5, self.timer_callback)"),
    Check("sigint_exit", "Ctrl+C ends it with exit code 0 and no traceback", 2,
          "in Jazzy rclpy.spin() may raise ExternalShutdownException on Ctrl+C: catch it together with "
          "KeyboardInterrupt"),
]


def _check_package_xml(s: GradingSession) -> None:
    found = source_package(s, PACKAGE)
    if found is None:
        s.record("depends_library", False, f"no package {PACKAGE} in src/", f"<depend>{LIBRARY}</depend>")
        return
    deps = run_dependencies(found[1])
    s.record("depends_library", LIBRARY in deps,
             f"package.xml dependencies: {', '.join(sorted(deps)) or 'none'}",
             f"{LIBRARY} among them (<depend>{LIBRARY}</depend>)")


def _shorten(text: str, limit: int = 110) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


def grade(s: GradingSession) -> None:
    """Run the node, read its /rosout records, judge them, then Ctrl+C it."""
    _check_package_xml(s)
    path = require_ros2_run_executable(s, "executable", PACKAGE, EXECUTABLE)
    if path is None:
        return
    rosout = s.ros.rosout()
    proc = s.launch(path, EXECUTABLE)
    if not wait_for_node(s, "node_name", proc, NODE) and proc.poll() is not None:
        s.skip_remaining(process_state(proc))
        record_sigint_exit(s, "sigint_exit", proc)
        return

    def squares() -> list:
        return rosout.records(level=INFO, match=lambda text: parse_square_line(text) is not None)

    def enough() -> bool:
        # SAMPLES square records, and the name record that follows the last one (or one more tick)
        count = len(squares())
        names = len(rosout.records(level=INFO, match=lambda text: parse_name_line(text) is not None))
        # (a node logging names but no square lines will not start now: stop waiting)
        return (count >= SAMPLES and (names >= SAMPLES or count > SAMPLES)) or (count == 0 and names >= SAMPLES)

    with s.phase("observe"):
        wait_until(enough, timeout=SAMPLES * PERIOD + 3.0 + LATE_DELIVERY, abort=lambda: proc.poll() is not None)
    records = squares()
    if not records:
        everything = rosout.records()
        texts = [f"[{r.name}] {_shorten(r.msg)}" for r in everything[:3]]
        observed = "no /rosout records" if not texts else "records: " + " | ".join(texts)
        if "sample_function_for_square_of_sum(" in proc.stdout():
            observed += "; the line appeared on stdout only (print() instead of the logger?)"
        s.record("square_log", False, f"{observed}; {process_state(proc)}", f"INFO records '{SQUARE_FORMAT}'")
        named = rosout.records(level=INFO, match=lambda text: parse_name_line(text) is not None)
        if named:  # the name lines can still be judged
            busiest = max({r.name for r in named}, key=lambda name: sum(r.name == name for r in named))
            _judge_names(s, [r for r in named if r.name == busiest])
        s.skip_remaining(f"no '{SQUARE_FORMAT}' record to judge")
        record_sigint_exit(s, "sigint_exit", proc)
        return
    loggers = sorted({r.name for r in records})
    main = max(loggers, key=lambda name: sum(r.name == name for r in records))
    mine = [r for r in records if r.name == main]
    s.record("square_log", True, f"{len(mine)} records like '{_shorten(mine[0].msg)}' from {main}",
             f"INFO records '{SQUARE_FORMAT}'")
    _judge_values(s, [parse_square_line(r.msg) for r in mine], mine)

    # this node's records of either kind, in order (other lines it may log are ignored)
    ordered = [r for r in rosout.records(node=main, level=INFO) if classify(r.msg) != "other"]
    _judge_names(s, ordered)
    record_rate(s, "rate", [stamp_seconds(r.stamp) for r in mine], period=PERIOD, needed=SAMPLES,
                waited=SAMPLES * PERIOD + 3.0, noun="record", source="the records' stamps")
    record_sigint_exit(s, "sigint_exit", proc)


def _judge_values(s: GradingSession, lines: list, records: list) -> None:
    """``ranges`` and ``square_values`` over every parsed square record."""
    out_of_range = [r.msg for line, r in zip(lines, records) if not line.ranges_ok()]
    s.record("ranges", not out_of_range,
             f"all {len(lines)} records in range" if not out_of_range
             else f"{len(out_of_range)}/{len(lines)} out of range, e.g. '{_shorten(out_of_range[0])}'",
             "0 <= a <= 1 and 1 <= b <= 2 in every record")
    wrong = [(line, r.msg) for line, r in zip(lines, records) if not line.square_ok()]
    if not wrong:
        observed = f"c == (a+b)**2 in all {len(lines)} records"
    else:
        line, text = wrong[0]
        observed = (f"{len(wrong)}/{len(lines)} records wrong, e.g. '{_shorten(text)}': "
                    f"(a+b)**2 = {line.expected_c()!r}, logged c = {line.c!r}")
    s.record("square_values", not wrong, observed, "c == (a+b)**2 (within the digits printed)")


def _judge_names(s: GradingSession, ordered: list) -> None:
    """``name_log``, ``pairs`` and ``names_differ`` over the node's records in order."""
    names = [parse_name_line(r.msg) for r in ordered if classify(r.msg) == "name"]
    expected_name = f"INFO records '{NAME_FORMAT}', NAME ten ASCII letters"
    if not names:
        s.record("name_log", False, "no 'sample_class_with_random_name.get_name() returned ...' record from the node",
                 expected_name)
        s.record("pairs", False, "no name records to pair", "a name record right after each square-of-sum record")
        s.record("names_differ", False, "no names logged", "a different name in every record")
        return
    bad = [n for n in names if not is_ten_letters(n)]
    s.record("name_log", not bad,
             f"{len(names)} names like {names[0]!r}" if not bad
             else f"{len(bad)}/{len(names)} names are not ten ASCII letters, e.g. {bad[0]!r} ({len(bad[0])} characters)",
             expected_name)
    kinds = [classify(r.msg) for r in ordered]
    lonely = unpaired([(kind, stamp_seconds(r.stamp)) for kind, r in zip(kinds, ordered)], max_gap=PERIOD / 2)
    shown = " ".join("S" if k == "square" else "N" for k in kinds[:12])
    s.record("pairs", not lonely,
             f"{kinds.count('square')} square and {kinds.count('name')} name records alternate ({shown} ...)"
             if not lonely else f"order of records (S square, N name): {shown}{' ...' if len(kinds) > 12 else ''}"
             f"; {len(lonely)} not in a square-then-name pair logged together",
             "S N S N ...: in every tick the square-of-sum record, then at once the name record")
    distinct = len(set(names))
    s.record("names_differ", len(names) >= 2 and distinct == len(names),
             f"{distinct} different names in {len(names)} records"
             + (f" (repeated: {max(set(names), key=names.count)!r})" if distinct < len(names) else ""),
             "a new random name in every record")
