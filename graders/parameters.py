"""Grader for ``parameters`` (seed ch. 22.1-22.6; contract in shared/LESSONS.md).

Black-box: the node's parameters are read and changed through its parameter
services (what ``ros2 param list/get/set`` use), its messages are watched on
the topic, and it is started a second time with ``--ros-args -p`` overrides
(what ``ros2 run ... --ros-args -p name:=value`` does). The two runs are
independent parts: the overridden one runs in a graph of its own.
"""

from __future__ import annotations

import time

from ros2course import kit
from ros2course.kit import Check, Session, checks, params, parts
from ros2course.kit.quotes import (
    DEFAULTS,
    EXECUTABLE,
    NODE,
    PACKAGE,
    amazing_quote,
    counts_from_zero,
    id_counts,
    set_at_runtime,
    short,
)

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

RUNS = ("executable",)  # every check of a run needs the executable
CHECKS = [
    Check("build", "The package builds with colcon", 1),
    *checks.started("", "python_package_that_uses_parameters_and_launch_files",
                    "amazing_quote_configurable_publisher_node", "amazing_quote_configurable_publisher_node",
                    node_part="defaults"),
    Check("declared", "It declares quote, philosopher_name, topic_name and period", 2,
          "call self.declare_parameter(name, default) for each of the four parameters in __init__",
          needs=RUNS, part="defaults"),
    Check("defaults", "The parameters' defaults and types are the contract's", 2,
          "defaults: quote 'Use the force, Pikachu!', philosopher_name 'Uncle Ben', topic_name 'amazing_quote', "
          "period 0.5 (a float literal, so the parameter is a double)", needs=RUNS, part="defaults"),
    Check("default_messages", "With the defaults it publishes AmazingQuote on /amazing_quote with the default texts", 2,
          "create the publisher on the topic_name parameter's value and fill quote/philosopher_name from the parameters",
          needs=RUNS, part="defaults"),
    Check("default_ids", "The id counts up by 1 from one message to the next, as in publisher-subscriber", 1,
          "keep the id in an attribute (self.incremental_id), put it in each message, then add 1",
          needs=RUNS, part="defaults"),
    Check("default_ids_from_zero", "The id starts at 0, as in publisher-subscriber", 1,
          "set self.incremental_id = 0 in __init__, and add 1 after publishing, not before",
          needs=RUNS, part="defaults"),
    Check("default_rate", "With the defaults it publishes at 2 Hz (period 0.5 s)", 2,
          "create the timer with the period parameter's value: self.create_timer(timer_period, self.timer_callback)",
          needs=RUNS, part="defaults"),
    Check("runtime_change", "Setting quote and philosopher_name at runtime changes the next messages", 3,
          "read quote and philosopher_name with self.get_parameter(...) inside the timer callback, "
          "not once in __init__", needs=RUNS, part="defaults"),
    checks.ctrl_c("sigint_exit", "it", 1,
          "in Jazzy rclpy.spin() may raise ExternalShutdownException on Ctrl+C: catch it together with KeyboardInterrupt",
          needs=RUNS, part="defaults"),
    Check("configured_topic", "Started with -p topic_name:=..., it publishes on that topic", 2,
          "read topic_name with self.get_parameter('topic_name') after declaring it, and pass it to create_publisher",
          needs=RUNS, part="configured"),
    Check("configured_rate", "Started with -p period:=0.25, it publishes at 4 Hz", 2,
          "read period with self.get_parameter('period') after declaring it, and pass it to create_timer",
          needs=("configured_topic",), part="configured"),
]


def grade(s: Session) -> None:
    """Run the node with its defaults (messages, then read/set its parameters, Ctrl+C), and at the same time
    with overrides, in a graph of its own (its own domain id: its messages cannot mix in)."""
    path = kit.executable(s, "executable", PACKAGE, EXECUTABLE)
    parts.at_once(s, "configured", lambda: _configured_run(s, path), "defaults", lambda: _defaults(s, path),
                  own_graphs={"configured"})


def _defaults(s: Session, path) -> None:
    """The run with the defaults: node_name, default_messages, default_rate, declared, runtime_change."""
    probe = s.graph.topic(DEFAULT_TOPIC, amazing_quote(s))
    began = time.monotonic()
    # a misnamed node is still graded through its parameter services (need_node=False)
    node = kit.start_node(s, "node_name", path, NODE, sigint_check="sigint_exit", need_node=False)
    _default_messages(s, probe, node.proc, began)
    counts_from_zero(s, "default_ids_from_zero", [m for _, m in probe.samples()], path, DEFAULT_TOPIC,
                     amazing_quote(s), DEFAULT_PERIOD, where=f" on {DEFAULT_TOPIC}",
                     sequence=next(iter(probe.sequence_numbers()), None))
    services = params.connect(s, node.name, proc=node.proc, why=s.results["node_name"].observed)
    params.declared(s, "declared", "defaults", services, DEFAULTS)
    set_at_runtime(s, "runtime_change", services, probe, node.proc, quote=RUNTIME_QUOTE,
                   philosopher=RUNTIME_PHILOSOPHER, count=RUNTIME_MESSAGES, period=DEFAULT_PERIOD,
                   topic=DEFAULT_TOPIC)


def _default_messages(s: Session, probe, proc, began: float) -> None:
    """``default_messages``, ``default_ids`` and ``default_rate`` from the messages on /amazing_quote (rate on
    send stamps)."""
    with s.phase("observe"):
        timeout = probe.observe(DEFAULT_SAMPLES, DEFAULT_PERIOD, max(0.5, START_TIMEOUT - (time.monotonic() - began)),
                                abort=lambda: proc.poll() is not None)
    samples = probe.samples()
    expected = (f"AmazingQuote messages on {DEFAULT_TOPIC} with quote {DEFAULTS['quote']!r} "
                f"and philosopher_name {DEFAULTS['philosopher_name']!r}")
    odd = [m for _, m in samples if m.quote != DEFAULTS["quote"] or m.philosopher_name != DEFAULTS["philosopher_name"]]
    if not samples:
        s.record("default_messages", False, f"no message on {DEFAULT_TOPIC} within {timeout:.1f} s; "
                 f"topics seen: {kit.topics_seen(s.ros)}; {kit.process_state(proc)}", expected)
    else:
        s.record("default_messages", not odd, f"{len(samples)} message(s); " + (
            f"e.g. quote {short(odd[0].quote)}, philosopher_name {short(odd[0].philosopher_name)}"
            if odd else "all with the defaults"), expected)
    id_counts(s, "default_ids", [m for _, m in samples], f" on {DEFAULT_TOPIC}")
    kit.rate(s, "default_rate", probe.send_stamps(), period=DEFAULT_PERIOD, needed=DEFAULT_SAMPLES,
             waited=timeout, noun="message", source="the messages' send stamps")


def _configured_run(s: Session, path) -> None:
    """``configured_topic`` and ``configured_rate`` from the run started with ``--ros-args -p`` overrides."""
    probe = s.graph.topic(f"/{CONFIGURED_TOPIC}", amazing_quote(s))  # the part's own graph
    args = ["--ros-args", "-p", f"topic_name:={CONFIGURED_TOPIC}", "-p", f"period:={CONFIGURED_PERIOD}"]
    proc = s.launch(path, f"{EXECUTABLE}.configured", args)
    began = time.monotonic()
    shown = f"-p topic_name:={CONFIGURED_TOPIC} -p period:={CONFIGURED_PERIOD}"
    with s.phase("observe"):
        probe.observe(CONFIGURED_SAMPLES, CONFIGURED_PERIOD, max(0.5, START_TIMEOUT - (time.monotonic() - began)),
                      abort=lambda: proc.poll() is not None)
    timeout = time.monotonic() - began
    count = len(probe.samples())
    s.record("configured_topic", count > 0, f"started with {shown}: " + (
        f"{count} message(s) on /{CONFIGURED_TOPIC}" if count else f"no message on /{CONFIGURED_TOPIC} within "
        f"{timeout:.1f} s; topics seen: {kit.topics_seen(s.graph)}; {kit.process_state(proc)}"),
        f"AmazingQuote messages on /{CONFIGURED_TOPIC} when started with {shown}")
    kit.rate(s, "configured_rate", probe.send_stamps(), period=CONFIGURED_PERIOD, needed=CONFIGURED_SAMPLES,
             waited=timeout, noun="message", source="the messages' send stamps")
    with s.phase("stop"):
        proc.stop(sigint_timeout=2.0, sigterm_timeout=1.0)
