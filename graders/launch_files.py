"""Grader for ``launch-files`` (seed ch. 22.7-22.11 and 23; contract in shared/LESSONS.md).

The launch file is taken from where ``ros2 launch`` takes it: the installed
``share/<pkg>/launch/`` folder, and run with the real launch_ros as ``ros2
launch`` runs it (see :mod:`graders.kit.launch`; on the PyPI install launch_ros
comes from the source-built underlay). Then the graph is watched, black-box:
node name, topic, rate and message contents. The file is also read statically,
only to say which ``Node(...)`` actions it holds when launch started too little.
"""

from __future__ import annotations

import time

from course.run.probes import LATE_DELIVERY
from graders import kit
from graders.kit import Check, GradingSession, Unmet
from graders.kit.launch import (
    MODE_LAUNCH_ROS,
    LaunchRun,
    describe_launch_folder,
    start_launch_file,
)
from graders.kit.quotes import (
    EXECUTABLE,
    LAUNCH_FILE,
    LAUNCH_NODE,
    LAUNCH_PERIOD,
    LAUNCH_PHILOSOPHER,
    LAUNCH_QUOTE,
    LAUNCH_TOPIC,
    PACKAGE,
    amazing_quote,
    first_difference,
    package_share,
    package_source,
    short,
)

SAMPLES = 6  # messages -> 5 intervals at 4 Hz (the minimum shared/LESSONS.md asks for)
NODE_TIMEOUT = 10.0  # seconds for the node to appear (launch_ros start-up included)

#: Seconds of observation the contract needs: first message after one period, then 5 intervals.
WINDOW = SAMPLES * LAUNCH_PERIOD

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("launch_installed", f"launch/{LAUNCH_FILE} is installed in share/{PACKAGE}/launch", 2,
          "add (os.path.join('share', package_name, 'launch'), glob(os.path.join('launch', '*launch.[pxy][yma]*'))) "
          "to data_files in setup.py, then colcon build"),
    Check("launch_starts", "The launch file starts amazing_quote_configurable_publisher_node", 2,
          "a Node(package='python_package_that_uses_parameters_and_launch_files', "
          "executable='amazing_quote_configurable_publisher_node', ...) in the LaunchDescription returned by "
          "generate_launch_description()"),
    Check("node_name", f"The node is named {LAUNCH_NODE}", 2, f"give Node(...) name='{LAUNCH_NODE}'"),
    Check("topic", f"It publishes AmazingQuote on /{LAUNCH_TOPIC}", 2,
          f"parameters=[{{'topic_name': '{LAUNCH_TOPIC}', ...}}] in Node(...)"),
    Check("rate", "It publishes at 4 Hz (period 0.25 s)", 2, "'period': 0.25 in the parameters dict (a float)",
          needs=("topic",)),
    Check("contents", "The messages carry the ch. 22.9 quote and philosopher Tyler", 2,
          "'quote' and 'philosopher_name': 'Tyler' in the parameters dict; adjacent string literals are glued "
          "without a space, so mind the spaces at the ends of the pieces", needs=("topic",)),
]


def _find_launch_file(s: GradingSession):
    """Record ``launch_installed``; return the file to run (installed, else the source one).

    Raises:
        Unmet: the package has no such launch file at all.
    """
    share = package_share(s)
    installed = share / "launch" / LAUNCH_FILE if share else None
    expected = f"install/{PACKAGE}/share/{PACKAGE}/launch/{LAUNCH_FILE}"
    if installed is not None and installed.is_file():
        s.record("launch_installed", True, str(installed.relative_to(s.workspace_root))
                 if installed.is_relative_to(s.workspace_root) else str(installed), expected)
        return installed
    source = package_source(s)
    in_source = source / "launch" / LAUNCH_FILE if source else None
    where = describe_launch_folder(share, PACKAGE)
    if in_source is not None and in_source.is_file():
        where += (f"; src/.../launch/{LAUNCH_FILE} exists but setup.py does not install it "
                  "(the remaining checks run that source file)")
        s.record("launch_installed", False, where, expected)
        return in_source
    s.record("launch_installed", False, where + f"; no launch/{LAUNCH_FILE} in the package's source either",
             expected, f"create launch/{LAUNCH_FILE} in the package and install it from setup.py's data_files")
    raise Unmet(f"there is no {LAUNCH_FILE} to launch")


def _record_start(s: GradingSession, run: LaunchRun, node_found: bool) -> bool:
    """Record ``launch_starts`` after waiting for the node; True when launch started the configurable publisher.

    Judged on launch's own "process started" report for the executable, or on the node being there.
    """
    expected = f"the launch file starts {PACKAGE}/{EXECUTABLE}"
    proc = run.processes[0]
    output = proc.stdout() + "\n" + proc.stderr()
    reported = f"[{EXECUTABLE}-" in output and "process started" in output
    if reported or node_found:
        return s.record("launch_starts", True, f"{MODE_LAUNCH_ROS}: launch started {EXECUTABLE}", expected)
    tail = " | ".join(output.strip().splitlines()[-3:])
    contents = run.file_contents()
    return s.record("launch_starts", False, f"{MODE_LAUNCH_ROS}: launch did not report starting {EXECUTABLE}; "
                    f"{kit.process_state(proc)}" + (f"; last output: {tail}" if tail else "")
                    + (f"; {contents}" if contents else ""), expected)


def grade(s: GradingSession) -> None:
    """Start the launch file, then watch the node, its topic, rate and messages."""
    launch_file = _find_launch_file(s)
    probe = s.ros.topic(f"/{LAUNCH_TOPIC}", amazing_quote(s))
    with s.phase("start"):
        run = start_launch_file(s, launch_file)
    mode = MODE_LAUNCH_ROS
    began = time.monotonic()
    first_other: list[float] = []

    def give_up() -> bool:
        if not run.any_running():
            return True
        # launch_ros's own helper node (launch_ros_<pid>) is not one of the learner's
        if not first_other and [n for n in s.ros.node_names() if not n.startswith("/launch_ros_")]:
            first_other.append(time.monotonic())
        return bool(first_other) and time.monotonic() - first_other[0] > 3.0

    with s.phase("start"):
        found = s.ros.wait_for_node(LAUNCH_NODE, NODE_TIMEOUT, abort=give_up)
    _record_start(s, run, found)
    seen = ", ".join(s.ros.node_names()) or "none"
    states = "; ".join(f"{p.name}: {kit.process_state(p)}" for p in run.processes)
    s.record("node_name", found, f"node /{LAUNCH_NODE} is running ({mode})" if found else
             f"no node named {LAUNCH_NODE} after {time.monotonic() - began:.1f} s; nodes seen: {seen}; {states}",
             f"a node named {LAUNCH_NODE} (Node(name=...) renames the node)")
    if not run.any_running():
        raise Unmet(f"nothing the launch file started is running: {states}")
    with s.phase("observe"):
        timeout = probe.observe(SAMPLES, LAUNCH_PERIOD, 4.0 + LATE_DELIVERY, abort=lambda: not run.any_running())
    samples = probe.samples()
    s.record("topic", bool(samples), f"{len(samples)} AmazingQuote message(s) on /{LAUNCH_TOPIC} ({mode})"
             if samples else f"no message on /{LAUNCH_TOPIC} within {timeout:.1f} s ({mode}); "
             f"topics seen: {kit.topics_seen(s.ros)}", f"AmazingQuote messages on /{LAUNCH_TOPIC}")
    kit.rate(s, "rate", probe.send_stamps(), period=LAUNCH_PERIOD, needed=SAMPLES, waited=timeout,
             noun="message", source="the messages' send stamps")
    wrong = [m for _, m in samples if m.quote != LAUNCH_QUOTE or m.philosopher_name != LAUNCH_PHILOSOPHER]
    expected = f"quote {short(LAUNCH_QUOTE)} (ch. 22.9), philosopher_name {LAUNCH_PHILOSOPHER!r}"
    if not wrong:
        s.record("contents", True, f"all {len(samples)} messages carry the quote and {LAUNCH_PHILOSOPHER!r}", expected)
    else:
        msg = wrong[0]
        parts = []
        if msg.quote != LAUNCH_QUOTE:
            parts.append(f"quote {short(msg.quote)} {first_difference(msg.quote, LAUNCH_QUOTE)}")
        if msg.philosopher_name != LAUNCH_PHILOSOPHER:
            parts.append(f"philosopher_name {msg.philosopher_name!r}")
        s.record("contents", False, f"{len(wrong)} of {len(samples)} messages differ: " + "; ".join(parts), expected)
    with s.phase("stop"):
        for proc in run.processes:
            proc.stop(sigint_timeout=3.0, sigterm_timeout=2.0)
