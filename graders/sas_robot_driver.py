"""Grader for ``sas-robot-driver`` (seed ch. 29-31; contract in shared/LESSONS.md, sas facts in ROS_ENV.md).

Black-box, so the same grader judges the Python driver of the lesson and the
seed's C++ driver built on the real ``sas`` packages:

* **The launch file** ``launch/real_robot_launch.py`` must be installed in
  ``share/sas_robot_driver_myrobot/launch`` and start the driver as
  ``myrobot_1`` with the seed's parameters (read statically, see
  :mod:`graders.kit.launch`).
* **The driver** is started the way launch_ros starts that ``Node`` action
  (``--ros-args -r __node:=myrobot_1 --params-file TMP.yaml``) with the seed's
  parameters (ch. 31.7). The grader watches ``/myrobot_1/get/joint_states``
  with :class:`graders.kit.joint_stream.JointStreamProbe` (rate at 500 Hz, six
  positions, zeros after ``connect()``, increasing stamps), reads the limits
  topics (radians), sends a sequence of targets on
  ``/myrobot_1/set/target_joint_positions`` (it is the only publisher there)
  and measures how fast the stream follows each, sends a target of the wrong
  size, and presses Ctrl+C.
* **The client** ``joint_interface_example`` runs in a graph of its own where
  the grader plays the driver: it publishes joint states but no limits first
  (the client must not send anything: it is not enabled yet), then the limits
  too, and records the targets the client streams (100 Hz, within 10 degrees
  of the initial positions, actually moving). The grader only *subscribes* to
  ``set/target_joint_positions`` there: newer sas drivers refuse a second
  publisher on their ``set/`` topics (shared/ROS_ENV.md).
"""

from __future__ import annotations

import contextlib
import math
import time
from pathlib import Path
from typing import Any

from course.env import foreign_python_prefix
from course.grading import Check, GradingSession
from course.probes import wait_until
from graders._common import process_state, record_sigint_exit, wait_for_node
from graders.kit.joint_stream import (
    JointSample,
    JointStreamProbe,
    arrival_rate,
    source_rate,
)
from graders.kit.launch import NodeAction, describe_launch_folder, read_launch_file, start_node_action

PACKAGE = "sas_robot_driver_myrobot"
DRIVER_EXECUTABLE = "sas_robot_driver_myrobot_node"
CLIENT_EXECUTABLE = "joint_interface_example"
NODE = "myrobot_1"
LAUNCH_FILE = "real_robot_launch.py"
JOINTS = 6
#: The seed's launch file parameters (ch. 31.7); limits in degrees.
PARAMETERS: dict[str, Any] = {
    "ip": "127.0.0.1",
    "joint_limits_min": [-360.0, -360.0, -360.0, -360.0, -360.0, -720.0],
    "joint_limits_max": [360.0, 360.0, 360.0, 360.0, 360.0, 720.0],
    "thread_sampling_time_sec": 0.002,
}
PERIOD = PARAMETERS["thread_sampling_time_sec"]  # seconds: 500 Hz (seed ch. 31.7)
RATE_TOLERANCE = 0.15  # on the mean period (shared/LESSONS.md)
RATE_SPAN = 1.0  # seconds of stream the rate is measured over (500 intervals at 500 Hz)
#: Joint targets (radians) sent in turn; all inside the limits, every joint different.
TARGETS = [
    [0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
    [-0.5, 0.25, -1.0, 1.5, -0.75, 3.0],
    [0.0, -0.3, 0.6, -0.9, 1.2, -1.5],
]
TRACK_LATENCY = 0.1  # seconds: the stream shows a target this soon after it is sent
TRACK_GIVE_UP = 0.5  # seconds waited per target before calling it not followed
RESEND = 0.01  # seconds between repeated publications of a target (a client streams them too)
WRONG_TARGET = [0.7, 0.7, 0.7, 0.7, 0.7]  # five values: must never be applied
WRONG_WATCH = 0.3  # seconds the stream is watched after the wrong-size target
SAME = 1e-9  # radians: "equal" for values the driver must pass through unchanged
ERROR = 40  # rcl_interfaces/msg/Log.ERROR

CLIENT_PERIOD = 0.01  # seconds: the client sends a target every 10 ms (seed ch. 31.9)
CLIENT_AMPLITUDE = math.radians(10.0)  # radians around the initial positions (seed ch. 31.9)
CLIENT_MIN_SWING = math.radians(1.0)  # radians each joint must move over the window to count as moving
CLIENT_DISABLED = 0.5  # seconds of joint states without limits: the client must stay silent
CLIENT_WINDOW = 1.5  # seconds of targets judged
CLIENT_STREAM_PERIOD = 0.01  # seconds between the stand-in driver's joint states
#: The stand-in driver's joint positions (radians): not zeros, so a client must read them.
INITIAL = [0.1, -0.2, 0.3, 0.4, -0.5, 0.6]

#: Seconds of observation: stream rate, target tracking, wrong-size watch, client silent + client targets.
WINDOW = RATE_SPAN + len(TARGETS) * TRACK_LATENCY + WRONG_WATCH + CLIENT_DISABLED + CLIENT_WINDOW

JOINT_STATES = f"/{NODE}/get/joint_states"
LIMITS_MIN = f"/{NODE}/get/joint_positions_min"
LIMITS_MAX = f"/{NODE}/get/joint_positions_max"
TARGET_TOPIC = f"/{NODE}/set/target_joint_positions"

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("launch_file", f"launch/{LAUNCH_FILE} is installed and starts the driver as {NODE} with the seed's "
          "parameters", 2,
          "install launch/*_launch.py from setup.py's data_files to share/<package>/launch, and give Node(...) "
          f"package='{PACKAGE}', executable='{DRIVER_EXECUTABLE}', name='{NODE}' and the parameters of ch. 31.7"),
    Check("executable", f"ros2 run finds {DRIVER_EXECUTABLE}", 1,
          f"add '{DRIVER_EXECUTABLE} = {PACKAGE}.{DRIVER_EXECUTABLE}:main' to console_scripts in setup.py"),
    Check("driver_starts", f"The driver runs as node {NODE}", 1,
          "create one Node in main() and do not exit: a missing parameter or an exception in __init__ ends it"),
    Check("interface", f"It has the sas topics under /{NODE}/", 2,
          "use the node's name as the prefix: f'{node.get_name()}/get/joint_states' and so on (ROS_ENV.md list)"),
    Check("stream_rate", "Joint states stream at 500 Hz (every thread_sampling_time_sec)", 3,
          "run the loop with self.create_timer(thread_sampling_time_sec, ...) and read the parameter, "
          "do not hard-code another period"),
    Check("stream_shape", "Each joint state has 6 positions and an increasing stamp", 2,
          "fill msg.position with the 6 joint positions and msg.header.stamp with node.get_clock().now().to_msg()"),
    Check("zeros_at_start", "The positions are zeros after connect()", 1,
          "connect() sets the joint positions to six zeros, as the seed's driver does"),
    Check("limits_published", "Both limits topics are published (6 values each)", 2,
          "publish get/joint_positions_min and get/joint_positions_max in every loop, like sas does"),
    Check("limits_radians", "The limits are the parameters converted to radians", 2,
          "the parameters are in degrees: convert with numpy.deg2rad before publishing"),
    Check("tracking", f"The stream follows each target within {TRACK_LATENCY:.1f} s", 3,
          "store the latest target in the subscriber callback and apply it with set_target_joint_positions "
          "in the next loop iteration"),
    Check("wrong_size", "A target of the wrong size is not applied (error logged)", 2,
          "set_target_joint_positions must raise on a vector whose size is not 6; catch it in the loop, log "
          "an error and keep the previous positions (or end cleanly, as sas does)"),
    Check("sigint_exit", "Ctrl+C ends the driver with exit code 0 and no traceback", 2,
          "catch (KeyboardInterrupt, ExternalShutdownException) around the loop, then deinitialize() and "
          "disconnect() in finally"),
    Check("client_executable", f"ros2 run finds {CLIENT_EXECUTABLE}", 1,
          f"add '{CLIENT_EXECUTABLE} = {PACKAGE}.{CLIENT_EXECUTABLE}:main' to console_scripts in setup.py"),
    Check("client_waits", "The client sends nothing before the driver is enabled", 2,
          "loop on rdi.is_enabled() (joint states AND both limits received) before reading positions"),
    Check("client_topic", f"The client is the one publisher of Float64MultiArray on {TARGET_TOPIC}", 1,
          "send targets with one publisher on 'myrobot_1/set/target_joint_positions' (RobotDriverClient)"),
    Check("client_rate", "The client sends a target every 10 ms (100 Hz)", 2,
          "use Clock(0.01): clock.update_and_sleep() once per loop iteration"),
    Check("client_targets", "Targets have 6 values within 10 degrees of the initial positions", 2,
          "target = joint_positions + numpy.deg2rad([10.0 * sin(...)] * 6), with joint_positions read once "
          "after the driver is enabled"),
    Check("client_moves", "Every joint of the targets actually moves", 1,
          "make the offset depend on the loop counter i, e.g. 10.0 * sin(i / (50.0 * pi)) degrees"),
]

DRIVER_CHECKS = ["driver_starts", "interface", "stream_rate", "stream_shape", "zeros_at_start",
                 "limits_published", "limits_radians", "tracking", "wrong_size", "sigint_exit"]
CLIENT_CHECKS = ["client_waits", "client_topic", "client_rate", "client_targets", "client_moves"]


# --- helpers -------------------------------------------------------------------------------------


def _skip(s: GradingSession, ids: list[str], reason: str) -> None:
    """Mark ``ids`` (those not recorded yet) as failed because of ``reason``."""
    for check_id in ids:
        if check_id not in s.results:
            s.record(check_id, False, f"not checked: {reason}", "(depends on the failed check above)")
            s.results[check_id].skipped = True


def _fmt(values, digits: int = 3) -> str:
    """``[0.100, -0.200, ...]`` for a short list of floats."""
    return "[" + ", ".join(f"{v:.{digits}f}" for v in values) + "]"


def _same(a, b, tol: float = SAME) -> bool:
    return len(a) == len(b) and all(abs(x - y) <= tol for x, y in zip(a, b))


def _topics_seen(graph) -> str:
    hidden = {"/rosout", "/parameter_events"}
    topics = {n: t for n, t in graph.topic_types().items() if n not in hidden}
    return ", ".join(f"{n} ({', '.join(t)})" for n, t in sorted(topics.items())) or "none"


def _driver_action() -> NodeAction:
    """The seed's launch file ``Node`` action (ch. 31.7), as the grader starts it."""
    return NodeAction(line=0, package=PACKAGE, executable=DRIVER_EXECUTABLE, name=NODE,
                      parameters=[dict(PARAMETERS)])


def _add_plot(s: GradingSession, title: str, times: list[float], series: dict[str, list[float]],
              unit: str, points: int = 60) -> None:
    """Hand a downsampled plot (~``points`` samples; times in seconds) to ``check`` if the engine draws plots."""
    if not hasattr(s, "add_plot") or len(times) < 2:
        return
    step = max(1, len(times) // points)
    index = list(range(0, len(times), step))
    if index[-1] != len(times) - 1:
        index.append(len(times) - 1)
    with contextlib.suppress(Exception):  # a plot must never cost the learner a grade
        s.add_plot(title, [times[i] for i in index], {k: [v[i] for i in index] for k, v in series.items()}, unit)


# --- the launch file -----------------------------------------------------------------------------


def _check_launch_file(s: GradingSession) -> None:
    """Record ``launch_file``: installed, and its Node action is the seed's (read statically, never run)."""
    share = s.find_share(PACKAGE)
    expected = (f"install/{PACKAGE}/share/{PACKAGE}/launch/{LAUNCH_FILE} with Node(package='{PACKAGE}', "
                f"executable='{DRIVER_EXECUTABLE}', name='{NODE}', parameters=[{{ip, joint_limits_min, "
                "joint_limits_max (degrees, ch. 31.7), thread_sampling_time_sec: 0.002}])")
    installed = share / "launch" / LAUNCH_FILE if share else None
    if installed is None or not installed.is_file():
        where = describe_launch_folder(share, PACKAGE)
        if share is not None and not (share / "launch").is_dir():
            where += " (is it in setup.py's data_files?)"
        s.record("launch_file", False, where, expected)
        return
    found = read_launch_file(installed)
    if found.problems:
        s.record("launch_file", False, "; ".join(found.problems), expected)
        return
    ours = [n for n in found.nodes if n.executable == DRIVER_EXECUTABLE]
    if not ours:
        listed = "; ".join(n.describe() for n in found.nodes) or "no Node(...) action"
        s.record("launch_file", False, f"{LAUNCH_FILE} starts: {listed}", expected)
        return
    action = ours[0]
    problems = list(action.unsupported)
    if action.package != PACKAGE:
        problems.append(f"package={action.package!r}")
    if action.name != NODE:
        problems.append(f"name={action.name!r}")
    params: dict[str, Any] = {}
    for item in action.parameters:
        if isinstance(item, dict):
            params.update(item)
        else:
            problems.append(f"a parameters file ({item}) the grader cannot check; write the values in a dict")
    for key, wanted in PARAMETERS.items():
        if key not in params:
            problems.append(f"no parameter {key}")
        elif key == "ip":
            if not isinstance(params[key], str):
                problems.append(f"ip={params[key]!r} is not a string")
        elif isinstance(wanted, list):
            got = params[key]
            if not (isinstance(got, list) and _same([float(x) for x in got], wanted, 1e-9)
                    and all(isinstance(x, float) for x in got)):
                problems.append(f"{key}={got!r} (wanted {wanted}, floats: a ROS double array)")
        elif not (isinstance(params[key], float) and abs(params[key] - wanted) < 1e-12):
            problems.append(f"{key}={params[key]!r} (wanted {wanted})")
    rel = installed.relative_to(s.workspace_root) if installed.is_relative_to(s.workspace_root) else installed
    if problems:
        s.record("launch_file", False, f"{rel}: {action.describe()}: " + "; ".join(problems), expected)
    else:
        s.record("launch_file", True, f"{rel}: {action.describe()} with the seed's parameters", expected)


# --- the driver ----------------------------------------------------------------------------------


def _record_interface(s: GradingSession) -> bool:
    """Record ``interface``: the three published topics and the target subscription, with their types."""
    wanted = {JOINT_STATES: "sensor_msgs/msg/JointState", LIMITS_MIN: "std_msgs/msg/Float64MultiArray",
              LIMITS_MAX: "std_msgs/msg/Float64MultiArray", TARGET_TOPIC: "std_msgs/msg/Float64MultiArray"}
    node = s.ros.node
    problems = []

    def missing() -> list[str]:
        types = s.ros.topic_types()
        out = []
        for topic, type_name in wanted.items():
            if type_name not in types.get(topic, []):
                out.append(topic)
            elif topic == TARGET_TOPIC and node.count_subscribers(topic) < 1:
                out.append(topic)
            elif topic != TARGET_TOPIC and node.count_publishers(topic) < 1:
                out.append(topic)
        return out

    wait_until(lambda: not missing(), 1.0, interval=0.05)
    types = s.ros.topic_types()
    for topic in missing():
        got = types.get(topic)
        role = "subscription" if topic == TARGET_TOPIC else "publisher"
        problems.append(f"no {role} of {wanted[topic]} on {topic}" + (f" (type {', '.join(got)})" if got else ""))
    expected = ("publishers of " + ", ".join(f"{t} ({wanted[t]})" for t in (JOINT_STATES, LIMITS_MIN, LIMITS_MAX))
                + f"; a subscription on {TARGET_TOPIC} ({wanted[TARGET_TOPIC]})")
    if problems:
        return s.record("interface", False, "; ".join(problems) + f"; topics seen: {_topics_seen(s.ros)}", expected)
    return s.record("interface", True, "all four sas topics are there with the right types", expected)


def _record_stream(s: GradingSession, window: list[JointSample]) -> None:
    """Record ``stream_rate``, ``stream_shape`` and ``zeros_at_start`` on the samples of the rate window."""
    stats = source_rate(window)
    hz = arrival_rate(window)
    expected = (f"{1 / PERIOD:.0f} Hz: mean period {PERIOD * 1000:.1f} ms ± {RATE_TOLERANCE:.0%} over at least "
                f"{RATE_SPAN:.1f} s of messages, computed like ros2 topic hz but over the DDS source timestamps "
                "(the publication times, not disturbed by the grader's own scheduling)")
    if stats is None or window[-1].source - window[0].source < RATE_SPAN * 0.9:
        span = window[-1].source - window[0].source if len(window) > 1 else 0.0
        s.record("stream_rate", False, f"only {len(window)} message(s) over {span:.2f} s"
                 + (f": {stats.describe()}" if stats else ""), expected)
    else:
        observed = (f"{stats.rate_hz:.1f} Hz (mean period {stats.mean_period * 1000:.2f} ms, min "
                    f"{stats.min_period * 1000:.2f}, max {stats.max_period * 1000:.2f}, {stats.samples} intervals)"
                    + (f"; ros2 topic hz (arrival times) would show {hz.rate_hz:.1f} Hz" if hz else ""))
        s.record("stream_rate", stats.within(1.0 / PERIOD, RATE_TOLERANCE), observed, expected)
    sizes = sorted({len(x.positions) for x in window})
    stamps = [x.stamp for x in window]
    backwards = sum(1 for a, b in zip(stamps, stamps[1:]) if b <= a)
    problems = []
    if sizes != [JOINTS]:
        problems.append(f"position sizes seen: {', '.join(map(str, sizes))}")
    if all(t == 0.0 for t in stamps):
        problems.append("every header.stamp is 0 (never set)")
    elif backwards:
        problems.append(f"{backwards} of {len(stamps) - 1} stamps are not later than the previous one")
    s.record("stream_shape", not problems, "; ".join(problems) if problems else
             f"{len(window)} messages, each with {JOINTS} positions, stamps increasing",
             f"{JOINTS} positions per message; header.stamp increasing from message to message")
    not_zero = [x for x in window if any(p != 0.0 for p in x.positions)]
    s.record("zeros_at_start", not not_zero and bool(window),
             f"first positions {_fmt(window[0].positions)}; {len(not_zero)} of {len(window)} messages before the "
             "first target are not all zeros" if not_zero else f"all {len(window)} messages before the first "
             "target are zeros", f"{JOINTS} zeros until a target arrives (connect() sets the positions to zeros)")


def _record_limits(s: GradingSession, probe: JointStreamProbe, alive) -> None:
    """Record ``limits_published`` and ``limits_radians`` from the first message on each limits topic."""
    from std_msgs.msg import Float64MultiArray  # noqa: PLC0415

    got = probe.first_messages([LIMITS_MIN, LIMITS_MAX], Float64MultiArray, 1.0, abort=lambda: not alive())
    missing = [t for t, m in got.items() if m is None]
    expected = f"Float64MultiArray with {JOINTS} values on {LIMITS_MIN} and {LIMITS_MAX}"
    wrong_size = [f"{t} has {len(m.data)} values" for t, m in got.items() if m is not None and len(m.data) != JOINTS]
    if missing or wrong_size:
        s.record("limits_published", False, "; ".join([f"no message on {t} within 1.0 s" for t in missing]
                                                      + wrong_size), expected)
        _skip(s, ["limits_radians"], "no complete limits to compare")
        return
    s.record("limits_published", True, f"{JOINTS} values on both topics", expected)
    wanted = {LIMITS_MIN: [math.radians(x) for x in PARAMETERS["joint_limits_min"]],
              LIMITS_MAX: [math.radians(x) for x in PARAMETERS["joint_limits_max"]]}
    degrees = {LIMITS_MIN: PARAMETERS["joint_limits_min"], LIMITS_MAX: PARAMETERS["joint_limits_max"]}
    problems = []
    for topic, msg in got.items():
        data = list(msg.data)
        if _same(data, wanted[topic], 1e-9):
            continue
        note = " (the degrees, not converted to radians)" if _same(data, degrees[topic], 1e-9) else ""
        problems.append(f"{topic} = {_fmt(data)}{note}")
    expected = (f"min {_fmt(wanted[LIMITS_MIN])}, max {_fmt(wanted[LIMITS_MAX])} rad "
                f"(the parameters {PARAMETERS['joint_limits_min']} / {PARAMETERS['joint_limits_max']} degrees)")
    s.record("limits_radians", not problems, "; ".join(problems) if problems else "both equal the parameters "
             "in radians", expected)


def _record_tracking(s: GradingSession, probe: JointStreamProbe, publisher: Any, alive) -> list[float] | None:
    """Send each target of :data:`TARGETS`; record ``tracking``. Returns the last target followed (or None)."""
    from std_msgs.msg import Float64MultiArray  # noqa: PLC0415

    latencies: list[float | None] = []
    last_followed = None
    for target in TARGETS:
        msg = Float64MultiArray(data=[float(x) for x in target])
        sent = time.monotonic()
        seen = None
        next_send = sent
        while time.monotonic() - sent < TRACK_GIVE_UP and alive():
            if time.monotonic() >= next_send:
                publisher.publish(msg)
                next_send += RESEND
            hit = [x for x in probe.samples(since=sent) if _same(x.positions, target)]
            if hit:
                seen = hit[0].arrival - sent
                break
            time.sleep(0.002)
        # hold the target until the latency bound is over, so the plot shows each step
        time.sleep(max(0.0, sent + TRACK_LATENCY - time.monotonic()))
        latencies.append(seen)
        if seen is not None:
            last_followed = target
    shown = ", ".join(f"{lat * 1000:.0f} ms" if lat is not None else f"not within {TRACK_GIVE_UP:.1f} s"
                      for lat in latencies)
    followed = sum(1 for lat in latencies if lat is not None and lat <= TRACK_LATENCY)
    expected = (f"each of {len(TARGETS)} targets (radians, sent on {TARGET_TOPIC}) shows up as the streamed "
                f"positions within {TRACK_LATENCY * 1000:.0f} ms")
    observed = f"latencies: {shown}"
    if followed < len(TARGETS):
        last = probe.samples()
        observed += (f"; streamed positions now {_fmt(last[-1].positions)}" if last else "")
        if not alive():
            observed += "; the driver stopped"
    s.record("tracking", followed == len(TARGETS), observed, expected, fraction=followed / len(TARGETS))
    return last_followed


def _record_wrong_size(s: GradingSession, probe: JointStreamProbe, publisher: Any, proc, rosout,
                       previous: list[float] | None) -> None:
    """Send a 5-value target; record ``wrong_size`` (not applied; error logged; or a clean exit)."""
    from std_msgs.msg import Float64MultiArray  # noqa: PLC0415

    msg = Float64MultiArray(data=list(WRONG_TARGET))
    sent = time.monotonic()
    for _ in range(3):
        publisher.publish(msg)
        time.sleep(RESEND)
    wait_until(lambda: proc.poll() is not None, WRONG_WATCH - 3 * RESEND, interval=0.01)
    after = probe.samples(since=sent)
    applied = [x for x in after if len(x.positions) != JOINTS
               or (previous is not None and not _same(x.positions, previous))]
    errors = rosout.records(level=ERROR)
    expected = (f"after a target of {len(WRONG_TARGET)} values: no message with other positions than the last "
                f"valid target, and an ERROR log record; or the driver ends cleanly (exit code 0), as sas does")
    code = proc.poll()
    if applied:
        first = applied[0]
        s.record("wrong_size", False, f"{len(applied)} of {len(after)} messages after it changed: first has "
                 f"{len(first.positions)} positions {_fmt(first.positions)}", expected)
    elif code is not None and code != 0:
        s.record("wrong_size", False, f"it was not applied but the driver died: {process_state(proc)}", expected)
    elif code == 0:
        s.record("wrong_size", True, "the driver logged and ended cleanly (exit code 0)"
                 + (f": {errors[0].msg}" if errors else ""), expected)
    elif not errors:
        s.record("wrong_size", False, f"not applied ({len(after)} messages kept the previous positions), but no "
                 "ERROR record on /rosout", expected, "log the rejected target with self.get_logger().error(...)",
                 fraction=0.5)
    else:
        s.record("wrong_size", True, f"not applied: {len(after)} messages kept the previous positions; "
                 f"logged: {errors[0].msg}", expected)


def _plot_driver(s: GradingSession, samples: list[JointSample]) -> None:
    if not samples:
        return
    start = samples[0].arrival
    good = [x for x in samples if len(x.positions) == JOINTS]
    _add_plot(s, f"{JOINT_STATES} (driver window)", [x.arrival - start for x in good],
              {f"joint {j + 1}": [math.degrees(x.positions[j]) for x in good] for j in range(JOINTS)}, "deg")


def _grade_driver(s: GradingSession, path: Path) -> None:
    """Start the driver as launch_ros would, watch and drive it, then Ctrl+C it."""
    from std_msgs.msg import Float64MultiArray  # noqa: PLC0415

    rosout = s.ros.rosout()
    probe = JointStreamProbe(s.ros.context, JOINT_STATES)
    try:
        proc, reason = start_node_action(s, _driver_action(), DRIVER_EXECUTABLE)
        if proc is None:
            _skip(s, DRIVER_CHECKS, reason)
            return
        if not wait_for_node(s, "driver_starts", proc, NODE):
            if proc.poll() is not None:
                _skip(s, DRIVER_CHECKS, process_state(proc))
                return

        def alive() -> bool:
            return proc.poll() is None

        with s.phase("observe"):
            probe.wait_for(bool, 3.0, abort=lambda: not alive())
        _record_interface(s)
        if not probe.count():
            _skip(s, ["stream_rate", "stream_shape", "zeros_at_start", "tracking", "wrong_size"],
                  f"no message on {JOINT_STATES}; {process_state(proc)}")
            _record_limits(s, probe, alive)
            if alive():
                record_sigint_exit(s, "sigint_exit", proc)
            else:
                _skip(s, ["sigint_exit"], process_state(proc))
            return
        with s.phase("observe"):
            window = probe.wait_for_span(RATE_SPAN, RATE_SPAN + 1.0, abort=lambda: not alive())
        _record_stream(s, window)
        _record_limits(s, probe, alive)
        publisher = s.ros.node.create_publisher(Float64MultiArray, TARGET_TOPIC, 1)
        try:
            wait_until(lambda: publisher.get_subscription_count() >= 1, 2.0, interval=0.01,
                       abort=lambda: not alive())
            with s.phase("observe"):
                previous = _record_tracking(s, probe, publisher, alive)
                _record_wrong_size(s, probe, publisher, proc, rosout, previous)
        finally:
            s.ros.node.destroy_publisher(publisher)
        _plot_driver(s, probe.samples())
        if alive():
            record_sigint_exit(s, "sigint_exit", proc)
        elif proc.poll() == 0:
            _sigint_second_run(s, probe)
        else:
            record_sigint_exit(s, "sigint_exit", proc)
    finally:
        probe.close()


def _sigint_second_run(s: GradingSession, probe: JointStreamProbe) -> None:
    """The driver ended cleanly on the wrong-size target (as sas does): Ctrl+C a fresh instance instead."""
    before = probe.count()
    proc, reason = start_node_action(s, _driver_action(), DRIVER_EXECUTABLE + ".second")
    if proc is None:
        _skip(s, ["sigint_exit"], reason)
        return
    with s.phase("start"):
        probe.wait_for(lambda got: len(got) > before, 10.0, abort=lambda: proc.poll() is not None)
    record_sigint_exit(s, "sigint_exit", proc)


# --- the client ----------------------------------------------------------------------------------


class _StandInDriver:
    """The grader playing ``myrobot_1`` for the client: joint states, later limits; targets recorded."""

    def __init__(self, graph) -> None:
        from rclpy.qos import QoSProfile  # noqa: PLC0415
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Float64MultiArray

        node = graph.node
        self.graph = graph
        self.enabled = False
        self._state = JointState(position=list(INITIAL))
        self._min = Float64MultiArray(data=[math.radians(x) for x in PARAMETERS["joint_limits_min"]])
        self._max = Float64MultiArray(data=[math.radians(x) for x in PARAMETERS["joint_limits_max"]])
        sas_qos = QoSProfile(depth=1)
        self.states = node.create_publisher(JointState, JOINT_STATES, sas_qos)
        self.limits_min = node.create_publisher(Float64MultiArray, LIMITS_MIN, sas_qos)
        self.limits_max = node.create_publisher(Float64MultiArray, LIMITS_MAX, sas_qos)
        self.targets = JointStreamProbe(graph.context, TARGET_TOPIC, "_ros2course_targets", Float64MultiArray)
        self._node = node
        self._timer = None

    def start(self) -> None:
        """Publish joint states every :data:`CLIENT_STREAM_PERIOD` s (limits too once :attr:`enabled`)."""
        self._timer = self._node.create_timer(CLIENT_STREAM_PERIOD, self._tick)

    def _tick(self) -> None:
        self._state.header.stamp = self._node.get_clock().now().to_msg()
        self.states.publish(self._state)
        if self.enabled:
            self.limits_min.publish(self._min)
            self.limits_max.publish(self._max)

    def stop(self) -> None:
        """Stop publishing and recording."""
        if self._timer is not None:
            self._node.destroy_timer(self._timer)
            self._timer = None
        self.targets.close()


def _grade_client(s: GradingSession, proc, driver: _StandInDriver) -> None:
    """Play the driver for the running client and judge what it sends."""
    graph = driver.graph
    node = graph.node

    def alive() -> bool:
        return proc.poll() is None

    with s.phase("start"):
        subscribed = wait_until(lambda: node.count_subscribers(JOINT_STATES) >= 1, 10.0, interval=0.02,
                                abort=lambda: not alive())
    if not subscribed:
        seen = ", ".join(graph.node_names()) or "none"
        _skip(s, CLIENT_CHECKS, f"the client never subscribed to {JOINT_STATES}; nodes seen: {seen}; "
              f"topics seen: {_topics_seen(graph)}; {process_state(proc)}")
        return
    driver.start()
    with s.phase("observe"):
        wait_until(lambda: driver.states.get_subscription_count() >= 1, 2.0, interval=0.01)
        time.sleep(CLIENT_DISABLED)
    enabled_at = time.monotonic()
    driver.enabled = True
    early = driver.targets.samples()
    expected = (f"no target on {TARGET_TOPIC} while the driver sent joint states but no limits "
                f"({CLIENT_DISABLED:.1f} s): the client is not enabled yet")
    s.record("client_waits", not early, f"{len(early)} target(s) arrived before the limits were published"
             + (f", the first {_fmt(early[0].positions)}" if early else "") if early else
             f"nothing sent during {CLIENT_DISABLED:.1f} s of joint states without limits", expected)

    def enough() -> bool:
        got = driver.targets.samples(since=enabled_at)
        return len(got) >= 2 and got[-1].source - got[0].source >= CLIENT_WINDOW

    with s.phase("observe"):
        wait_until(enough, CLIENT_WINDOW + 2.0, interval=0.02, abort=lambda: not alive())
    got = driver.targets.samples(since=enabled_at)
    publishers = node.get_publishers_info_by_topic(TARGET_TOPIC)
    types = sorted({p.topic_type for p in publishers})
    expected = f"targets (std_msgs/msg/Float64MultiArray) from exactly one publisher on {TARGET_TOPIC}"
    if not got:
        s.record("client_topic", False, f"no target within {CLIENT_WINDOW + 2.0:.1f} s after the driver was "
                 f"enabled; topics seen: {_topics_seen(graph)}; {process_state(proc)}", expected)
        _skip(s, ["client_rate", "client_targets", "client_moves"], f"no target on {TARGET_TOPIC}")
        return
    s.record("client_topic", len(publishers) == 1, f"{len(got)} targets; {len(publishers)} publisher(s) of "
             f"{', '.join(types) or '?'}", expected,
             "create the target publisher once (RobotDriverClient), not one per message or per loop"
             if len(publishers) > 1 else None)
    times = [x.source for x in got]
    stats = source_rate(got)
    expected = (f"{1 / CLIENT_PERIOD:.0f} Hz: mean period {CLIENT_PERIOD * 1000:.0f} ms ± {RATE_TOLERANCE:.0%} "
                f"over at least {CLIENT_WINDOW:.1f} s (like ros2 topic hz, over the DDS source timestamps)")
    span = times[-1] - times[0]
    if stats is None or span < CLIENT_WINDOW * 0.9:
        s.record("client_rate", False, f"{len(got)} target(s) over {span:.2f} s"
                 + (f": {stats.describe()}" if stats else "") + f"; {process_state(proc)}", expected)
    else:
        s.record("client_rate", stats.within(1.0 / CLIENT_PERIOD, RATE_TOLERANCE), stats.describe(), expected)
    data = [list(x.positions) for x in got]
    bad_size = [d for d in data if len(d) != JOINTS]
    offsets = [[v - i for v, i in zip(d, INITIAL)] for d in data if len(d) == JOINTS]
    worst = max((abs(o) for row in offsets for o in row), default=0.0)
    expected = (f"{JOINTS} values each, within {math.degrees(CLIENT_AMPLITUDE):.0f} degrees of the driver's "
                f"initial positions {_fmt(INITIAL)} rad")
    if bad_size:
        s.record("client_targets", False, f"{len(bad_size)} of {len(data)} targets have "
                 f"{len(bad_size[0])} values", expected)
    else:
        s.record("client_targets", worst <= CLIENT_AMPLITUDE + 1e-6,
                 f"largest offset from the initial positions: {math.degrees(worst):.2f} degrees "
                 f"(first target {_fmt(data[0])})", expected)
    swings = [max(col) - min(col) for col in zip(*offsets)] if offsets else []
    still = [j + 1 for j, sw in enumerate(swings) if sw < CLIENT_MIN_SWING]
    expected = (f"every joint's target moves by at least {math.degrees(CLIENT_MIN_SWING):.0f} degree over "
                f"{CLIENT_WINDOW:.1f} s")
    s.record("client_moves", bool(swings) and not still,
             "swing per joint: " + ", ".join(f"{math.degrees(sw):.2f}" for sw in swings) + " degrees"
             + (f"; joints {still} do not move" if still else ""), expected)
    if offsets:
        start = times[0]
        _add_plot(s, f"{CLIENT_EXECUTABLE} targets (offset from the initial positions)",
                  [t - start for t in times[:len(offsets)]],
                  {f"joint {j + 1}": [math.degrees(row[j]) for row in offsets] for j in range(JOINTS)}, "deg")


# --- entry point ---------------------------------------------------------------------------------


def grade(s: GradingSession) -> None:
    """Check the launch file, grade the driver, then the client (started early, in a graph of its own)."""
    _check_launch_file(s)
    driver_path, observed = s.find_executable(PACKAGE, DRIVER_EXECUTABLE)
    s.record("executable", driver_path is not None, observed,
             f"ros2 run {PACKAGE} {DRIVER_EXECUTABLE} finds install/{PACKAGE}/lib/{PACKAGE}/{DRIVER_EXECUTABLE}")
    client_path, observed = s.find_executable(PACKAGE, CLIENT_EXECUTABLE)
    if client_path is None:  # the seed installs it as joint_interface_example.py (LESSONS.md: both names)
        with_suffix, also = s.find_executable(PACKAGE, CLIENT_EXECUTABLE + ".py")
        if with_suffix is not None:
            client_path, observed = with_suffix, also
    s.record("client_executable", client_path is not None, observed,
             f"ros2 run {PACKAGE} {CLIENT_EXECUTABLE} (or {CLIENT_EXECUTABLE}.py) finds "
             f"install/{PACKAGE}/lib/{PACKAGE}/{CLIENT_EXECUTABLE}")
    client = stand_in = None
    if client_path is not None:
        # The client starts now, in a graph of its own, and waits for a driver there while the real
        # driver is graded: its start-up overlaps the driver's, and the two never see each other.
        graph = s.new_graph()
        stand_in = _StandInDriver(graph)
        # the seed's #!/usr/bin/python3 is the system Python on a pip install: use ours (course.env)
        interpreter = foreign_python_prefix(client_path)
        client = (s.launch(Path(interpreter[0]), CLIENT_EXECUTABLE, [str(client_path)], graph=graph) if interpreter
                  else s.launch(client_path, CLIENT_EXECUTABLE, graph=graph))
    else:
        _skip(s, CLIENT_CHECKS, f"there is no {CLIENT_EXECUTABLE} executable to run")
    if driver_path is not None:
        _grade_driver(s, driver_path)
    else:
        _skip(s, DRIVER_CHECKS, f"there is no {DRIVER_EXECUTABLE} executable to run")
    if client is not None:
        try:
            _grade_client(s, client, stand_in)
        finally:
            stand_in.stop()
            with s.phase("stop"):
                client.stop(sigint_timeout=2.0, sigterm_timeout=2.0)
