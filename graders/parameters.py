"""Grader for ``parameters`` (seed ch. 22.1-22.6; contract in shared/LESSONS.md).

Black-box: the node's parameters are read and changed through its parameter
services (what ``ros2 param list/get/set`` use), its messages are watched on
the topic, and it is started a second time with ``--ros-args -p`` overrides
(what ``ros2 run ... --ros-args -p name:=value`` does).
"""

from __future__ import annotations

import time

from course.grading import Check, GradingSession
from course.probes import parameter_client, wait_future
from graders._common import process_state, record_rate, record_sigint_exit, require_executable, wait_for_node
from graders.kit.quotes import (DEFAULTS, EXECUTABLE, NODE, PACKAGE, amazing_quote, parameter_value,
                             short, topics_seen)

DEFAULT_TOPIC = "/amazing_quote"
DEFAULT_PERIOD = 0.5  # seconds (seed ch. 22.3)
DEFAULT_SAMPLES = 6  # messages -> 5 intervals (shared/LESSONS.md minimum)
#: The second run's overrides: a topic of the grader's and a 4 Hz period.
CONFIGURED_TOPIC = "ros2course_configured_quote"
CONFIGURED_PERIOD = 0.25  # seconds
CONFIGURED_SAMPLES = 6  # messages -> 5 intervals (shared/LESSONS.md minimum)
#: Values set at runtime (the seed's ros2 param set example, ch. 24.5, reworded).
RUNTIME_QUOTE = "You got a good-guy heart. You can't do anything about it, that's just who you are."
RUNTIME_PHILOSOPHER = "Zak"
#: A changed parameter must show within this many messages (one may already be on its way: seed ch. 24.5).
RUNTIME_MESSAGES = 2
#: Seconds from a run's start to its first message (a Python node starts in about 1 s; a loaded machine is slower).
START_TIMEOUT = 10.0

#: Seconds of observation the contract needs: the defaults run (messages, then the runtime
#: change); the run with -p topic_name/period overlaps it in a graph of its own.
WINDOW = max(DEFAULT_SAMPLES * DEFAULT_PERIOD + RUNTIME_MESSAGES * DEFAULT_PERIOD,
             CONFIGURED_SAMPLES * CONFIGURED_PERIOD)

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("executable", "ros2 run finds amazing_quote_configurable_publisher_node", 1,
          "add 'amazing_quote_configurable_publisher_node = python_package_that_uses_parameters_and_launch_files."
          "amazing_quote_configurable_publisher_node:main' to console_scripts in setup.py, then colcon build"),
    Check("node_name", "A node named amazing_quote_configurable_publisher_node starts", 1,
          "pass 'amazing_quote_configurable_publisher_node' to super().__init__()"),
    Check("declared", "It declares quote, philosopher_name, topic_name and period", 2,
          "call self.declare_parameter(name, default) for each of the four parameters in __init__"),
    Check("defaults", "The parameters' defaults and types are the contract's", 2,
          "defaults: quote 'Use the force, Pikachu!', philosopher_name 'Uncle Ben', topic_name 'amazing_quote', "
          "period 0.5 (a float literal, so the parameter is a double)"),
    Check("default_messages", "With the defaults it publishes AmazingQuote on /amazing_quote with the default texts", 2,
          "create the publisher on the topic_name parameter's value and fill quote/philosopher_name from the parameters"),
    Check("default_rate", "With the defaults it publishes at 2 Hz (period 0.5 s)", 2,
          "create the timer with the period parameter's value: self.create_timer(timer_period, self.timer_callback)"),
    Check("runtime_change", "Setting quote and philosopher_name at runtime changes the next messages", 3,
          "read quote and philosopher_name with self.get_parameter(...) inside the timer callback, "
          "not once in __init__"),
    Check("sigint_exit", "Ctrl+C ends it with exit code 0 and no traceback", 1,
          "in Jazzy rclpy.spin() may raise ExternalShutdownException on Ctrl+C: catch it together with KeyboardInterrupt"),
    Check("configured_topic", "Started with -p topic_name:=..., it publishes on that topic", 2,
          "read topic_name with self.get_parameter('topic_name') after declaring it, and pass it to create_publisher"),
    Check("configured_rate", "Started with -p period:=0.25, it publishes at 4 Hz", 2,
          "read period with self.get_parameter('period') after declaring it, and pass it to create_timer"),
]


def _target_node(s: GradingSession, proc) -> str | None:
    """The node to talk to: the contract's name, or the learner's only node when it is misnamed."""
    if wait_for_node(s, "node_name", proc, NODE):
        return NODE
    names = s.ros.node_names()
    return names[0].lstrip("/") if len(names) == 1 and proc.poll() is None else None


def _check_parameters(s: GradingSession, client) -> None:
    """``declared`` and ``defaults``, through list_parameters / get_parameters."""
    names = list(wait_future(client.list_parameters(), 5.0).result.names)
    missing = [name for name in DEFAULTS if name not in names]
    s.record("declared", not missing,
             "declared parameters: " + (", ".join(sorted(names)) or "none")
             + (f"; missing: {', '.join(missing)}" if missing else ""),
             "quote, philosopher_name, topic_name and period among them")
    present = [name for name in DEFAULTS if name in names]
    if not present:
        s.record("defaults", False, "none of the four parameters is declared", _defaults_text())
        return
    values = wait_future(client.get_parameters(present), 5.0).values
    wrong, right = [], 0
    for name, value_msg in zip(present, values):
        kind, value = parameter_value(value_msg)
        wanted_kind = "double" if isinstance(DEFAULTS[name], float) else "string"
        if kind == wanted_kind and value == DEFAULTS[name]:
            right += 1
        else:
            wrong.append(f"{name} = {value!r} ({kind})")
    wrong += [f"{name} not declared" for name in missing]
    s.record("defaults", not wrong, "all four as expected" if not wrong else "; ".join(wrong), _defaults_text(),
             fraction=right / len(DEFAULTS))


def _defaults_text() -> str:
    return ", ".join(f"{name} = {value!r} ({'double' if isinstance(value, float) else 'string'})"
                     for name, value in DEFAULTS.items())


def _check_default_messages(s: GradingSession, probe, proc, began: float) -> None:
    """``default_messages`` and ``default_rate`` from the messages on /amazing_quote."""
    with s.phase("observe"):
        timeout = probe.observe(DEFAULT_SAMPLES, DEFAULT_PERIOD, max(0.5, START_TIMEOUT - (time.monotonic() - began)),
                                abort=lambda: proc.poll() is not None)
    samples = probe.samples()
    expected = (f"AmazingQuote messages on {DEFAULT_TOPIC} with quote {DEFAULTS['quote']!r} "
                f"and philosopher_name {DEFAULTS['philosopher_name']!r}")
    if not samples:
        s.record("default_messages", False, f"no message on {DEFAULT_TOPIC} within {timeout:.1f} s; "
                 f"topics seen: {topics_seen(s)}; {process_state(proc)}", expected)
        s.record("default_rate", False, "no message to time", f"2.00 Hz on {DEFAULT_TOPIC}")
        return
    odd = [m for _, m in samples if m.quote != DEFAULTS["quote"] or m.philosopher_name != DEFAULTS["philosopher_name"]]
    first = odd[0] if odd else samples[0][1]
    s.record("default_messages", not odd,
             f"{len(samples)} message(s); " + (f"e.g. quote {short(first.quote)}, philosopher_name "
                                                f"{short(first.philosopher_name)}" if odd else "all with the defaults"),
             expected)
    record_rate(s, "default_rate", probe.send_stamps(), period=DEFAULT_PERIOD, needed=DEFAULT_SAMPLES,
                waited=timeout, noun="message", source="the messages' send stamps")


def _check_runtime_change(s: GradingSession, client, probe, proc) -> None:
    """``runtime_change``: set quote/philosopher_name like ``ros2 param set``, then read the next messages."""
    from rclpy.parameter import Parameter  # noqa: PLC0415

    expected = (f"within {RUNTIME_MESSAGES} messages after the change, quote {short(RUNTIME_QUOTE)} "
                f"and philosopher_name {RUNTIME_PHILOSOPHER!r}")
    if not probe.samples():
        s.record("runtime_change", False, f"no message on {DEFAULT_TOPIC} to compare with", expected)
        return
    response = wait_future(client.set_parameters([Parameter("quote", value=RUNTIME_QUOTE),
                                                  Parameter("philosopher_name", value=RUNTIME_PHILOSOPHER)]), 5.0)
    failed = [f"{name}: {result.reason or 'refused'}"
              for name, result in zip(("quote", "philosopher_name"), response.results) if not result.successful]
    if failed:
        s.record("runtime_change", False, "set_parameters failed: " + "; ".join(failed), expected)
        return
    changed_at = time.time()  # the node applied the change before it answered: later send stamps are after it
    with s.phase("observe"):
        later = probe.wait_sent_after(changed_at, RUNTIME_MESSAGES, DEFAULT_PERIOD,
                                      abort=lambda: proc.poll() is not None)
    if not later:
        s.record("runtime_change", False, f"no message after the change; {process_state(proc)}", expected)
        return
    last = later[min(RUNTIME_MESSAGES, len(later)) - 1]
    quote_ok = last.quote == RUNTIME_QUOTE
    name_ok = last.philosopher_name == RUNTIME_PHILOSOPHER
    seen = ", ".join(f"({short(m.quote, 30)}, {m.philosopher_name!r})" for m in later[:RUNTIME_MESSAGES])
    verdict = "" if quote_ok and name_ok else (
        " -- the node still publishes the old values: does it read the parameters only once?")
    s.record("runtime_change", quote_ok and name_ok,
             f"set_parameters succeeded; the next {len(later[:RUNTIME_MESSAGES])} message(s) were {seen}{verdict}",
             expected, fraction=(quote_ok + name_ok) / 2)


def _start_configured_run(s: GradingSession, path):
    """Start the second run, with ``--ros-args -p`` overrides, in a graph of its own.

    It runs at the same time as the first run but in another ROS domain, so a
    node that ignores ``topic_name`` cannot put its second copy's messages on
    the first run's /amazing_quote (that made verdicts timing-dependent).
    """
    graph = s.new_graph()
    probe = graph.topic(f"/{CONFIGURED_TOPIC}", amazing_quote(s))
    args = ["--ros-args", "-p", f"topic_name:={CONFIGURED_TOPIC}", "-p", f"period:={CONFIGURED_PERIOD}"]
    proc = s.launch(path, f"{EXECUTABLE}.configured", args, graph=graph)
    return graph, proc, probe, time.monotonic()


def _check_configured_run(s: GradingSession, graph, proc, probe, began: float) -> None:
    """``configured_topic`` and ``configured_rate`` from the second instance's messages."""
    shown = f"-p topic_name:={CONFIGURED_TOPIC} -p period:={CONFIGURED_PERIOD}"
    with s.phase("observe"):
        probe.observe(CONFIGURED_SAMPLES, CONFIGURED_PERIOD, max(0.5, START_TIMEOUT - (time.monotonic() - began)),
                      abort=lambda: proc.poll() is not None)
    timeout = time.monotonic() - began
    samples = probe.samples()
    expected_topic = f"AmazingQuote messages on /{CONFIGURED_TOPIC} when started with {shown}"
    if not samples:
        s.record("configured_topic", False, f"started with {shown}: no message on /{CONFIGURED_TOPIC} within "
                 f"{time.monotonic() - began:.1f} s; topics seen: {topics_seen(s, graph)}; {process_state(proc)}",
                 expected_topic)
        s.record("configured_rate", False, "no message to time", f"4.00 Hz on /{CONFIGURED_TOPIC}")
    else:
        s.record("configured_topic", True, f"started with {shown}: {len(samples)} message(s) on /{CONFIGURED_TOPIC}",
                 expected_topic)
        record_rate(s, "configured_rate", probe.send_stamps(), period=CONFIGURED_PERIOD, needed=CONFIGURED_SAMPLES,
                    waited=timeout, noun="message", source="the messages' send stamps")
    with s.phase("stop"):
        proc.stop(sigint_timeout=2.0, sigterm_timeout=1.0)


def grade(s: GradingSession) -> None:
    """Run the node with its defaults, read/set its parameters, Ctrl+C it, then run it with overrides."""
    path = require_executable(s, "executable", PACKAGE, EXECUTABLE)
    if path is None:
        return
    configured = _start_configured_run(s, path)
    probe = s.ros.topic(DEFAULT_TOPIC, amazing_quote(s))
    began = time.monotonic()
    proc = s.launch(path, EXECUTABLE)
    target = _target_node(s, proc)
    if target is None:
        if proc.poll() is not None:
            for check_id in ("declared", "defaults", "default_messages", "default_rate", "runtime_change"):
                s.record(check_id, False, f"not checked: {process_state(proc)}", "a running node")
        else:
            for check_id in ("declared", "defaults", "runtime_change"):
                s.record(check_id, False, f"no node to ask: {s.results['node_name'].observed}",
                         f"the parameter services of /{NODE}")
            _check_default_messages(s, probe, proc, began)
    else:
        try:
            with parameter_client(s.ros, target, timeout=5.0) as client:
                _check_parameters(s, client)
                _check_default_messages(s, probe, proc, began)
                _check_runtime_change(s, client, probe, proc)
        except TimeoutError as exc:
            for check_id in ("declared", "defaults", "runtime_change"):
                if check_id not in s.results:
                    s.record(check_id, False, f"the parameter services of /{target} did not answer: {exc}; "
                             f"{process_state(proc)}", f"/{NODE} answers list/get/set_parameters")
            if "default_messages" not in s.results:
                _check_default_messages(s, probe, proc, began)
    record_sigint_exit(s, "sigint_exit", proc)
    _check_configured_run(s, *configured)
