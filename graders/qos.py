"""Grader for ``qos`` (issue 20; contract in chapters/qos/CONTRACT.md).

Black-box, on the graph's own QoS information (what ``ros2 topic info --verbose``
prints, judged with ``rclpy.qos.qos_check_compatible``) and on what the
grader's probes of chosen profiles receive:

* **sensor**: a BEST_EFFORT probe (``qos_profile_sensor_data``) must receive the
  10 Hz stream; a RELIABLE probe must not match the sensor publisher; the offer is VOLATILE.
* **config**: the grader changes the ``units`` parameter, then a
  TRANSIENT_LOCAL probe made after that (a late joiner) must receive the
  current configuration, and only it (depth 1).
* **monitor**: the grader publishes its own latched configuration *before* the
  monitor starts, and its own BEST_EFFORT temperatures; the monitor must log both.
* **cli**: the learner's ``cli/qos_topic_info.sh`` runs against two grader nodes of
  random names and must print their QoS (``ros2 topic info --verbose``).

Each executable is a part of its own (partial credit), ending with its Ctrl+C check.

rclpy and the message packages are imported inside the functions that grade: a grader module
is also loaded for its CHECKS alone (``ros2course list``, ``hint``), where ROS is not needed.
"""

from __future__ import annotations

import math
import re

from ros2course import kit
from ros2course.kit import LATE_DELIVERY, Check, GradingSession, Unmet, checks, scripts
from ros2course.kit import params as kit_params
from ros2course.kit import topics_services as ts

from . import _qos

PACKAGE = "python_package_that_uses_qos"
SENSOR_EXE = SENSOR_NODE = "sensor_publisher_node"
CONFIG_EXE = CONFIG_NODE = "config_publisher_node"
MONITOR_EXE = MONITOR_NODE = "sensor_monitor_node"
SENSOR_TOPIC = "/temperature"
SENSOR_TYPE = "sensor_msgs/msg/Temperature"
CONFIG_TOPIC = "/sensor_config"
CONFIG_TYPE = "std_msgs/msg/String"
FRAME_ID = "temperature_sensor"
PERIOD = 0.1  # seconds between readings (10 Hz)
#: Readings judged -> 19 intervals. At 10 Hz a machine running two checks at once delays one reading
#: by up to ~0.3 s now and then (seen in dev validate under a load of 10 on 2 cores); over 9 intervals
#: that alone moved a correct timer outside ±15 %, over 19 it stays inside.
SAMPLES = 20
#: The first reading is not judged: its timer's first tick comes while the process is still starting
#: (a late first stamp made the first interval 0.015 s in most runs).
WARM_UP = 1
START_TIMEOUT = 5.0  # seconds from the node appearing to its first reading
DEFAULT_UNITS = "celsius"
#: Temperatures of the grader's own the monitor must log (of the ones it published).
LOGGED_READINGS = 3
SCRIPT = "cli/qos_topic_info.sh"
SCRIPT_TIMEOUT = 25.0  # seconds; each `ros2` command takes ~1 s to start

#: Seconds of observation the contract needs: 21 readings at 10 Hz, the configuration change and the
#: late joiner's replay (one delivery each), 3 of the grader's readings logged by the monitor.
WINDOW = (WARM_UP + SAMPLES) * PERIOD + 2 * 0.5 + LOGGED_READINGS * PERIOD

SENSOR = {"part": "sensor", "needs": ("sensor_executable",)}
CONFIG = {"part": "config", "needs": ("config_executable",)}
MONITOR = {"part": "monitor", "needs": ("monitor_executable",)}
CLI = {"part": "cli", "needs": ("cli_script",)}
SENSOR_HINT = "create_publisher(Temperature, '/temperature', qos_profile_sensor_data) (from rclpy.qos)"
LATCHED_HINT = ("QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE, "
                "durability=DurabilityPolicy.TRANSIENT_LOCAL)")

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("depends", "package.xml depends on rclpy, std_msgs and sensor_msgs", 1,
          "add <depend>rclpy</depend>, <depend>std_msgs</depend> and <depend>sensor_msgs</depend> to package.xml"),
    *checks.started("sensor", PACKAGE, SENSOR_EXE, SENSOR_NODE, part="sensor"),
    Check("sensor_topic", f"It publishes {SENSOR_TOPIC} of type {SENSOR_TYPE}", 1, SENSOR_HINT, **SENSOR),
    Check("sensor_best_effort", "It offers BEST_EFFORT: a RELIABLE subscription never matches it", 2,
          "a reading lost is not worth resending: use qos_profile_sensor_data (BEST_EFFORT, VOLATILE, KEEP_LAST 5) "
          "instead of a plain depth", **SENSOR),
    Check("sensor_volatile", "It offers VOLATILE durability, as the sensor-data profile does", 1,
          "qos_profile_sensor_data is VOLATILE: a stale reading is never replayed to a subscription that joins later "
          "(TRANSIENT_LOCAL is for a latched configuration, not a stream)", **SENSOR),
    Check("sensor_stream", f"A BEST_EFFORT subscription receives the readings (frame_id {FRAME_ID!r})", 2,
          f"set msg.header.frame_id = '{FRAME_ID}' and msg.temperature, then publish", **SENSOR),
    Check("sensor_rate", "One reading every 0.1 s (10 Hz)", 2, "self.create_timer(0.1, self.timer_callback)",
          **SENSOR),
    checks.ctrl_c("sensor_sigint_exit", "the sensor publisher", **SENSOR),
    *checks.started("config", PACKAGE, CONFIG_EXE, CONFIG_NODE, part="config"),
    Check("config_topic", f"It publishes {CONFIG_TOPIC} of type {CONFIG_TYPE}", 1,
          f"create_publisher(String, '{CONFIG_TOPIC}', latched_qos)", **CONFIG),
    Check("config_initial", f"At start it publishes 'units: {DEFAULT_UNITS}' (the parameter's default), "
          "replayed to a later TRANSIENT_LOCAL subscription", 1,
          f"declare_parameter('units', '{DEFAULT_UNITS}'), create the latched publisher, then publish "
          f"String(data='units: {DEFAULT_UNITS}') once in __init__", **CONFIG),
    Check("config_republish", "Setting the parameter units publishes 'units: <new value>'", 1,
          "declare_parameter('units', 'celsius'); add_post_set_parameters_callback(...) publishes the new "
          "configuration", **CONFIG),
    Check("config_late_joiner", "A TRANSIENT_LOCAL subscription made after the configuration was published "
          "still receives it", 3, "durability=DurabilityPolicy.TRANSIENT_LOCAL on the publisher: it keeps its "
          "last messages for subscriptions that join later", **CONFIG),
    Check("config_depth", "The late joiner receives only the current configuration (KEEP_LAST, depth 1)", 2,
          "history=HistoryPolicy.KEEP_LAST, depth=1: the publisher keeps (and replays) only its last message",
          part="config", needs=("config_republish", "config_late_joiner")),
    Check("config_latched", "It offers RELIABLE and TRANSIENT_LOCAL (ros2 topic info --verbose)", 2, LATCHED_HINT,
          **CONFIG),
    checks.ctrl_c("config_sigint_exit", "the configuration publisher", **CONFIG),
    *checks.started("monitor", PACKAGE, MONITOR_EXE, MONITOR_NODE, part="monitor"),
    Check("monitor_topics", f"It subscribes to {SENSOR_TOPIC} ({SENSOR_TYPE}) and {CONFIG_TOPIC} ({CONFIG_TYPE})",
          1, "two create_subscription calls in __init__", **MONITOR),
    Check("monitor_sensor_qos", f"Its {SENSOR_TOPIC} subscription matches a BEST_EFFORT publisher", 2,
          "a RELIABLE request never matches a BEST_EFFORT offer: subscribe with qos_profile_sensor_data",
          **MONITOR),
    Check("monitor_config_qos", f"Its {CONFIG_TOPIC} subscription asks for the latched profile: RELIABLE, "
          "TRANSIENT_LOCAL", 2, "a VOLATILE subscription gets nothing published before it started; the monitor "
          "subscribes with the same latched profile as the publisher: " + LATCHED_HINT, **MONITOR),
    Check("monitor_logs_config", "It logs the configuration published before it started ('Config: ...')", 2,
          "self.get_logger().info(f'Config: {msg.data}') in the configuration callback", **MONITOR),
    Check("monitor_logs_sensor", "It logs the readings it receives ('Temperature: 21.50')", 2,
          "self.get_logger().info(f'Temperature: {msg.temperature:.2f}') in the temperature callback", **MONITOR),
    checks.ctrl_c("monitor_sigint_exit", "the monitor", **MONITOR),
    Check("cli_script", f"{SCRIPT} exists and is valid bash", 1, part="cli"),
    Check("cli_ends", "The script ends by itself, with exit code 0", 1, **CLI),
    Check("cli_sensor_qos", f"It prints the QoS of {SENSOR_TOPIC}'s publisher (Reliability: BEST_EFFORT)", 2,
          f"ros2 topic info --verbose {SENSOR_TOPIC}", **CLI),
    Check("cli_config_qos", f"It prints the QoS of {CONFIG_TOPIC}'s publisher (Durability: TRANSIENT_LOCAL)", 2,
          f"ros2 topic info --verbose {CONFIG_TOPIC}", **CLI),
]


def _types() -> tuple[type, type]:
    from sensor_msgs.msg import Temperature  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
    from std_msgs.msg import String  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    return Temperature, String


def _grade_sensor(s: GradingSession, temperature: type) -> None:
    path = kit.executable(s, "sensor_executable", PACKAGE, SENSOR_EXE)
    graph = s.graph  # the part's own
    # both probes exist before the node starts: no reading is missed, and the RELIABLE one would match at once
    best_effort = graph.topic(SENSOR_TOPIC, temperature, _qos.sensor_qos())
    reliable = _qos.Probe(graph, SENSOR_TOPIC, temperature, _qos.profile(reliable=True, transient_local=False,
                                                                         depth=10))
    node = kit.start_node(s, "sensor_node_name", path, SENSOR_NODE, sigint_check="sensor_sigint_exit",
                          need_node=False)
    target, where = ts.own_endpoint(s, "sensor_topic", node, "publishers", SENSOR_TOPIC, SENSOR_TYPE,
                                    none=f"no {SENSOR_TYPE} topic published to listen to", where="on")
    if target != SENSOR_TOPIC:  # grade what flows where it is published
        best_effort = graph.topic(target, temperature, _qos.sensor_qos())
        reliable = _qos.Probe(graph, target, temperature, reliable.qos)
    with s.phase("observe"):
        window = best_effort.observe(WARM_UP + SAMPLES, PERIOD, START_TIMEOUT, abort=node.ended)
    readings = best_effort.messages()[:WARM_UP + SAMPLES]

    profiles = _qos.wait_endpoint_qos(graph, target, node.name, "publishers")
    verdicts = [_qos.compatible(p, reliable.qos) for p in profiles]
    incompatible = bool(profiles) and not any(ok for ok, _ in verdicts)
    received = len(reliable.messages())
    offered = ", ".join(f"({_qos.describe(p)})" for p in profiles) or "no publisher in the graph"
    reason = next((r for ok, r in verdicts if not ok), "")
    s.record("sensor_best_effort", incompatible and received == 0,
             f"it offers {offered}{where}; a RELIABLE subscription "
             + (f"cannot match ({reason})" if incompatible else "matches it")
             + f"; the grader's RELIABLE probe received {received} reading(s)"
             + ("" if not reliable.incompatible.is_set() else " and got the incompatible-QoS event"),
             "BEST_EFFORT offered: qos_check_compatible(offered, RELIABLE request) is ERROR and the RELIABLE probe "
             "receives nothing")

    volatile = bool(profiles) and all(_qos.word(p.durability) == "VOLATILE" for p in profiles)
    s.record("sensor_volatile", volatile, f"it offers {offered}{where}",
             "VOLATILE (qos_profile_sensor_data: no reading is kept for subscriptions that join later)")

    if not readings:
        raise Unmet(f"no reading reached a BEST_EFFORT subscription on {target} in {window:.1f} s; "
                    f"{kit.process_state(node.proc)}")
    frames = sorted({m.header.frame_id for m in readings})
    good = [m for m in readings if m.header.frame_id == FRAME_ID and math.isfinite(m.temperature)]
    s.record("sensor_stream", len(good) == len(readings),
             f"{len(readings)} reading(s) received by a BEST_EFFORT (qos_profile_sensor_data) subscription{where}, "
             f"frame_id {', '.join(map(repr, frames))}, e.g. temperature {readings[0].temperature:.2f}",
             f"readings with header.frame_id {FRAME_ID!r} and a finite temperature",
             fraction=len(good) / len(readings))
    kit.rate(s, "sensor_rate", best_effort.send_stamps(WARM_UP + SAMPLES)[WARM_UP:], period=PERIOD, needed=SAMPLES,
             waited=window, noun="reading", source="the readings' send stamps, the first one left out", where=where)


def _grade_config(s: GradingSession, string: type) -> None:
    path = kit.executable(s, "config_executable", PACKAGE, CONFIG_EXE)
    node = kit.start_node(s, "config_node_name", path, CONFIG_NODE, sigint_check="config_sigint_exit",
                          need_node=False)
    target, where = ts.own_endpoint(s, "config_topic", node, "publishers", CONFIG_TOPIC, CONFIG_TYPE,
                                    none=f"no {CONFIG_TYPE} topic published", where="on")
    profiles = _qos.wait_endpoint_qos(s.ros, target, node.name, "publishers")
    # a VOLATILE listener of whatever reliability is offered: it sees the change whatever the
    # durability and reliability (those are judged by the late joiner and config_latched)
    reliable = bool(profiles) and all(_qos.word(p.reliability) == "RELIABLE" for p in profiles)
    early = _qos.Probe(s.ros, target, string, _qos.profile(reliable=reliable, transient_local=False, depth=10))
    # a RELIABLE, TRANSIENT_LOCAL subscription made after the node started, before units is set: what the
    # node published at start is replayed to it (a VOLATILE offer cannot match it: nothing to wait for)
    start = _qos.Probe(s.ros, target, string, _qos.profile(reliable=True, transient_local=True, depth=10))
    start_can_match = any(_qos.compatible(p, start.qos)[0] for p in profiles)

    # the configuration changes once: with depth 1 only the new one is kept for late joiners
    services = kit_params.connect(s, node.name, proc=node.proc)
    with s.phase("observe"):
        _qos.wait_for(lambda: early.matched() > 0, 3.0, abort=node.ended)  # else the new configuration is missed
        if start_can_match:  # before units is set: the first message replayed is the one of the start
            _qos.wait_for(lambda: bool(start.messages()), LATE_DELIVERY, abort=node.ended)
    initial = [m.data for m in start.messages()]
    wanted = f"units: {DEFAULT_UNITS}"
    s.record("config_initial", initial[:1] == [wanted],
             "a RELIABLE, TRANSIENT_LOCAL subscription made after the node started, before units was set, received "
             + (", ".join(map(repr, initial[:3])) or "nothing")
             + ("" if start_can_match or not profiles else
                f" (it cannot match the publisher's {', '.join(f'({_qos.describe(p)})' for p in profiles)})"),
             f"{wanted!r}, published at start and kept for subscriptions that join later")
    with s.phase("observe"):
        # The listener has matched the publisher; the publisher may learn of the listener a moment
        # later (discovery runs both ways) and a VOLATILE listener misses what is sent before: a
        # second change, to another unit, is the retry. The late joiner's verdicts use the last one.
        units, tried = "", []
        for patience in (1.5, LATE_DELIVERY):
            units = _qos.random_units(other_than=tried)
            tried.append(units)
            answers = services.set({"units": units})
            if _qos.wait_for(lambda u=units: any(m.data == f"units: {u}" for m in early.messages()), patience,
                             abort=node.ended):
                break
        latest = f"units: {units}"
    seen = [m.data for m in early.messages()]
    refused = [a.line() for a in answers if not a.successful]
    s.record("config_republish", latest in seen,
             f"after `ros2 param set /{node.name} units {units}`"
             + (f" ({'; '.join(refused)})" if refused else "")
             + f" the grader received {', '.join(map(repr, seen[-3:])) or 'nothing'} on {target}",
             f"{latest!r} published after the parameter changed")

    late = _qos.Probe(s.ros, target, string, _qos.profile(reliable=True, transient_local=True, depth=10))
    verdicts = [_qos.compatible(p, late.qos) for p in profiles]
    can_match = any(ok for ok, _ in verdicts)
    reason = next((r for ok, r in verdicts if not ok), "no publisher in the graph")
    offered = ", ".join(f"({_qos.describe(p)})" for p in profiles) or "no publisher"
    if can_match:
        with s.phase("observe"):
            _qos.wait_for(lambda: bool(late.messages()), LATE_DELIVERY, abort=node.ended)
            first = late.messages()[:1]
            if first and first[0].data != latest and latest in seen:  # an outdated one first: the rest follows
                _qos.wait_for(lambda: any(m.data == latest for m in late.messages()), 1.0)
    got = [m.data for m in late.messages()]
    shown = ", ".join(map(repr, got[:4])) + (" ..." if len(got) > 4 else "")
    s.record("config_late_joiner", bool(got),
             f"a TRANSIENT_LOCAL subscription made after the configuration was published received "
             f"{len(got)} message(s){': ' + shown if got else ''}"
             + ("" if can_match else f" (it cannot match the publisher's {offered}: {reason})") + where,
             "the configuration replayed to the late joiner (publisher TRANSIENT_LOCAL)")
    s.record("config_depth", got == [latest],
             f"the late joiner received {len(got)} message(s): {shown}",
             f"only the current configuration, {latest!r} (KEEP_LAST, depth 1)")
    latched = bool(profiles) and all(_qos.word(p.reliability) == "RELIABLE"
                                     and _qos.word(p.durability) == "TRANSIENT_LOCAL" for p in profiles)
    s.record("config_latched", latched, f"it offers {offered} on {target}", "RELIABLE, TRANSIENT_LOCAL")


def _matching(readings: list[float], text: str) -> list[float]:
    """The readings ``text`` logs as the lesson asks: ``Temperature: <value with two decimals>``."""
    return [r for r in readings if re.search(rf"Temperature: {r:.2f}(?![0-9])", text)]


def _grade_monitor(s: GradingSession, temperature: type, string: type) -> None:
    path = kit.executable(s, "monitor_executable", PACKAGE, MONITOR_EXE)
    graph = s.graph  # the part's own
    # the configuration is published before the monitor exists: it is a late joiner
    feed = _qos.Feed(s, graph, temperature, string, sensor_topic=SENSOR_TOPIC, config_topic=CONFIG_TOPIC,
                     period=PERIOD)
    rosout = graph.rosout()
    node = kit.start_node(s, "monitor_node_name", path, MONITOR_NODE, sigint_check="monitor_sigint_exit",
                          need_node=False)
    found: dict[str, list[str]] = {}

    def both() -> bool:
        found.clear()
        found.update(ts.endpoints(graph, node.name, "subscriptions"))
        return SENSOR_TOPIC in found and CONFIG_TOPIC in found

    with s.phase("start"):
        _qos.wait_for(both, 3.0, abort=node.ended)
    s.record("monitor_topics", SENSOR_TYPE in found.get(SENSOR_TOPIC, []) and CONFIG_TYPE in found.get(CONFIG_TOPIC, []),
             f"{node.name or 'the node'} subscribes to: {ts.describe_endpoints(found)}",
             f"{SENSOR_TOPIC} [{SENSOR_TYPE}] and {CONFIG_TOPIC} [{CONFIG_TYPE}]")
    if node.name is None:
        raise Unmet(f"no node to inspect; {kit.process_state(node.proc)}")

    requested = _qos.wait_endpoint_qos(graph, SENSOR_TOPIC, node.name, "subscriptions", 1.0)
    verdicts = [_qos.compatible(feed.sensor_offered, p) for p in requested]
    ok = bool(requested) and all(v for v, _ in verdicts)
    asked = ", ".join(f"({_qos.describe(p)})" for p in requested) or f"no subscription on {SENSOR_TOPIC}"
    reason = next((r for v, r in verdicts if not v), "")
    s.record("monitor_sensor_qos", ok, f"it requests {asked}" + (f": {reason}" if reason else ""),
             f"a request a BEST_EFFORT publisher ({_qos.describe(feed.sensor_offered)}) satisfies")
    requested = _qos.wait_endpoint_qos(graph, CONFIG_TOPIC, node.name, "subscriptions", 1.0)
    asked = ", ".join(f"({_qos.describe(p)})" for p in requested) or f"no subscription on {CONFIG_TOPIC}"
    latched = bool(requested) and all(_qos.word(p.durability) == "TRANSIENT_LOCAL"
                                      and _qos.word(p.reliability) == "RELIABLE"
                                      and _qos.compatible(feed.config_offered, p)[0] for p in requested)
    s.record("monitor_config_qos", latched, f"it requests {asked}",
             "the latched profile: RELIABLE, TRANSIENT_LOCAL (as the configuration publisher offers)")

    def records() -> list[str]:
        return [r.msg for r in rosout.records(node=node.name)]

    def logged_readings() -> list[float]:
        published = feed.published()
        return sorted({r for text in records() for r in _matching(published, text)})

    with s.phase("observe"):
        _qos.wait_for(lambda: any(f"Config: {feed.config}" in t for t in records())
                      and len(logged_readings()) >= LOGGED_READINGS, LATE_DELIVERY, abort=node.ended)
    texts = records()
    recent = " | ".join(t.strip()[:60] for t in texts[-2:]) or "no log records"
    config_logged = any(f"Config: {feed.config}" in t for t in texts)
    unlabelled = not config_logged and any(feed.config in t for t in texts)
    on_stdout = feed.config in node.proc.stdout()
    s.record("monitor_logs_config", config_logged,
             f"the grader published {feed.config!r} on {CONFIG_TOPIC} before the node started; "
             + ("it is in the node's log" if config_logged else
                "the node logged it without the label 'Config: '" if unlabelled else
                f"not in the node's log (last records: {recent})")
             + ("; it appeared on stdout only (print() instead of the logger?)" if on_stdout and not config_logged
                else ""),
             f"a log record containing 'Config: {feed.config}'")
    readings = logged_readings()
    s.record("monitor_logs_sensor", len(readings) >= LOGGED_READINGS,
             f"{len(readings)} of the grader's {len(feed.published())} readings found in the node's log"
             + (f", e.g. {readings[0]:.2f}" if readings else f" (last records: {recent})"),
             f"at least {LOGGED_READINGS} of the grader's random temperatures logged as 'Temperature: <value with "
             "two decimals>'",
             fraction=min(1.0, len(readings) / LOGGED_READINGS))


def _grade_cli(s: GradingSession, temperature: type, string: type) -> None:
    path = scripts.script(s, "cli_script", SCRIPT)
    graph = s.graph  # the part's own
    oracle = _qos.Oracle(s, graph, temperature, string, sensor_topic=SENSOR_TOPIC, config_topic=CONFIG_TOPIC)
    run = scripts.run_script(s, path, timeout=SCRIPT_TIMEOUT,
                             daemon_sees=[SENSOR_TOPIC, CONFIG_TOPIC, f"/{oracle.sensor_node}",
                                          f"/{oracle.config_node}"])
    scripts.ended(s, "cli_ends", run, "it ends by itself with exit code 0")
    scripts.printed(s, "cli_sensor_qos", run, [f"Node name: {oracle.sensor_node}", "Reliability: BEST_EFFORT"],
                    f"the QoS of the publisher of {SENSOR_TOPIC}", f"ros2 topic info --verbose {SENSOR_TOPIC}")
    scripts.printed(s, "cli_config_qos", run, [f"Node name: {oracle.config_node}", "Durability: TRANSIENT_LOCAL"],
                    f"the QoS of the publisher of {CONFIG_TOPIC}", f"ros2 topic info --verbose {CONFIG_TOPIC}")


def grade(s: GradingSession) -> None:
    """Grade the three nodes and the script, each a part of its own (see the module docstring)."""
    kit.depends(s, "depends", PACKAGE, ("rclpy", "std_msgs", "sensor_msgs"))
    temperature, string = _types()
    with s.part("config"):  # first, in s.ros: the parameter client of the kit asks there
        _grade_config(s, string)
    with s.part("sensor", own_graph=True):
        _grade_sensor(s, temperature)
    with s.part("monitor", own_graph=True):
        _grade_monitor(s, temperature, string)
    with s.part("cli", own_graph=True):
        _grade_cli(s, temperature, string)
