"""Grader for ``param-dump-load`` (seed ch. 24; contract in shared/LESSONS.md).

The learner keeps a parameters file in the ``ros2 param dump`` format at
``src/python_package_that_uses_parameters_and_launch_files/config/peanut_butter_falcon_quote_publisher_node.yaml``
(the lesson's fixed location), with a new quote. The grader:

1. reads the file (the contract is about the file): YAML, the fully qualified
   node name as top-level key, a ``ros__parameters`` mapping (the format
   ``ros2 param dump`` writes: ``yaml.dump({"/node": {"ros__parameters": {...}}})``,
   shared/ROS_ENV.md);
2. starts the configurable publisher as the launch-files lesson's launch file
   starts it (node name, parameters), with :func:`ros2course.kit.launch.start_node_action`;
3. compares the file's parameters with the ones the running node declares
   (names and types, through its parameter services);
4. loads the file into the running node as ``ros2 param load`` does
   (:func:`ros2course.kit.params.load_file`: rclpy's
   ``parameter_dict_from_yaml_file`` for this node, then one non-atomic
   ``set_parameters`` call, results reported per parameter);
5. watches ``/truly_inspirational_quote`` for the new quote.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ros2course.kit import Check, Session, params
from ros2course.kit.quotes import (
    LAUNCH_NODE,
    LAUNCH_PERIOD,
    LAUNCH_PHILOSOPHER,
    LAUNCH_QUOTE,
    LAUNCH_TOPIC,
    PACKAGE,
    amazing_quote,
    package_source,
    quote_after,
    short,
    start_as_launched,
)

CONFIG = Path("config") / f"{LAUNCH_NODE}.yaml"  # inside the package's source folder
NODE_KEY = f"/{LAUNCH_NODE}"
#: The parameters the configurable publisher declares (parameters lesson); the file must hold them all.
REQUIRED = ("period", "philosopher_name", "quote", "topic_name")
#: A loaded quote must show within this many messages (one may be on its way: seed ch. 24.5).
NEXT_MESSAGES = 3

#: Seconds of observation the contract needs: the loaded quote in the next messages at 4 Hz.
WINDOW = (NEXT_MESSAGES + 1) * LAUNCH_PERIOD

FILE_OK = ("node_key", "node_running")
CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("file_present", f"The parameters file is at src/{PACKAGE}/{CONFIG}", 1,
          f"save the dump as src/{PACKAGE}/{CONFIG}"),
    Check("yaml_valid", "The file is valid YAML", 1,
          "quote strings that contain ': ' or start with a quote character, and keep the indentation consistent",
          needs=("file_present",)),
    Check("node_key", f"Its top-level key is {NODE_KEY} with a ros__parameters mapping (the dump format)", 2,
          f"the file starts with '{NODE_KEY}:', then '  ros__parameters:', then the parameters indented below it",
          needs=("yaml_valid",)),
    Check("node_running", f"The node starts as the launch file starts it and publishes on /{LAUNCH_TOPIC}", 1,
          "the launch-files lesson's node must work first: run its check", needs=("yaml_valid",)),
    Check("parameter_types", "The file's parameters are the node's, with the node's types", 2,
          "period must stay a float (0.25, not '0.25' or 1); strings stay strings; only parameters the node has",
          needs=FILE_OK),
    Check("new_quote", "The file's quote is a new one (not the launch file's)", 1,
          "edit the quote: value in the file", needs=("node_key",)),
    Check("kept_values", f"The file keeps the launched node's period ({LAUNCH_PERIOD}) and topic_name "
          f"({LAUNCH_TOPIC})", 1, "dump the node started by the launch file (not one started by ros2 run with the "
          "defaults), then edit only the quote (and philosopher_name if you want)", needs=("node_key",)),
    Check("load", "Loading the file into the running node (ros2 param load) sets its parameters", 2,
          "every parameter in the file must be accepted by the node (names and types as it declares them)",
          needs=FILE_OK),
    Check("observed_quote", f"After loading, /{LAUNCH_TOPIC} carries the file's quote and philosopher", 2,
          "the node must read quote and philosopher_name on every publish (parameters lesson)", needs=("load",)),
]


def grade(s: Session) -> None:
    """Check the file, start the node as launched, load the file into it, watch for the new quote."""
    source = package_source(s)
    path = source / CONFIG if source else None
    values = params.read_dump(s, "file_present", "yaml_valid", "node_key", path, NODE_KEY,
                              shown=f"src/{PACKAGE}/{CONFIG}", absent=f"no package {PACKAGE} in src/",
                              search=s.workspace_root / "src", pattern=f"*{LAUNCH_NODE}*.yaml")
    _new_quote(s, values or {})  # judged on the file alone (needs node_key)
    _kept_values(s, values or {})
    probe = s.ros.topic(f"/{LAUNCH_TOPIC}", amazing_quote(s))
    proc = start_as_launched(s, "node_running", probe)
    s.require("node_key")
    services = params.connect(s, LAUNCH_NODE, proc=proc)
    params.file_types(s, "parameter_types", values, services.get(services.names()), REQUIRED)
    loaded_at = params.load_file(s, "load", services, path, NODE_KEY, must_set="quote")
    quote, philosopher = str(values.get("quote")), values.get("philosopher_name", LAUNCH_PHILOSOPHER)
    quote_after(s, "observed_quote", probe, loaded_at, count=NEXT_MESSAGES, period=LAUNCH_PERIOD, quote=quote,
                philosopher=philosopher, proc=proc, expected=f"within {NEXT_MESSAGES} messages after the load: "
                f"quote {short(quote)} and philosopher_name {philosopher!r}")
    with s.phase("stop"):
        proc.stop(sigint_timeout=3.0, sigterm_timeout=2.0)


def _new_quote(s: Session, values: dict[str, Any]) -> None:
    """``new_quote``: the file's quote is not the launch file's (read from the file alone)."""
    quote = values.get("quote")
    expected = f"a quote different from the launch file's ({short(LAUNCH_QUOTE, 40)})"
    if not isinstance(quote, str):
        s.record("new_quote", False, "no quote string in the file" if quote is None else f"quote is {quote!r}",
                 expected)
    else:
        s.record("new_quote", quote.strip() != LAUNCH_QUOTE, f"quote: {short(quote)}"
                 + (" (the launch file's, unchanged)" if quote.strip() == LAUNCH_QUOTE else ""), expected)


def _kept_values(s: Session, values: dict[str, Any]) -> None:
    """``kept_values``: the file's period and topic_name are those of the node the launch file starts (the lesson:
    dump the node started as the launch file starts it, then edit the quote). A file dumped from a node started
    with the defaults (period 0.5, topic amazing_quote) loads, and changes nothing a reader of the topic sees
    (the node reads both only at start-up), but it is not that node's file (helper audit of issue 37)."""
    period, topic = values.get("period"), values.get("topic_name")
    problems = []
    if not (isinstance(period, float) and abs(period - LAUNCH_PERIOD) < 1e-9):
        problems.append(f"period is {period!r}")
    if not (isinstance(topic, str) and topic.lstrip("/") == LAUNCH_TOPIC):
        problems.append(f"topic_name is {topic!r}")
    s.record("kept_values", not problems, "; ".join(problems) or f"period {period}, topic_name {topic!r}",
             f"period {LAUNCH_PERIOD} and topic_name '{LAUNCH_TOPIC}', as the launch file sets them (the dump of "
             "the launched node)")
