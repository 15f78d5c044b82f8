"""Grader for ``param-dump-load`` (seed ch. 24; contract in shared/LESSONS.md).

The learner keeps a parameters file in the ``ros2 param dump`` format at
``src/python_package_that_uses_parameters_and_launch_files/config/peanut_butter_falcon_quote_publisher_node.yaml``
(the lesson's fixed location), with a new quote. The grader:

1. reads the file (the contract is about the file): YAML, the fully qualified
   node name as top-level key, a ``ros__parameters`` mapping (the format
   ``ros2 param dump`` writes: ``yaml.dump({"/node": {"ros__parameters": {...}}})``,
   shared/ROS_ENV.md);
2. starts the configurable publisher as the launch-files lesson's launch file
   starts it (node name, parameters), with :func:`graders.kit.launch.start_node_action`;
3. compares the file's parameters with the ones the running node declares
   (names and types, through its parameter services);
4. loads the file into the running node as ``ros2 param load`` does
   (:meth:`graders.kit.params.NodeParameters.load`: rclpy's
   ``parameter_dict_from_yaml_file`` for this node, then one non-atomic
   ``set_parameters`` call, results reported per parameter);
5. watches ``/truly_inspirational_quote`` for the new quote.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from course.run.probes import LATE_DELIVERY
from graders import kit
from graders.kit import Check, GradingSession, Unmet, params
from graders.kit.launch import NodeAction, start_node_action
from graders.kit.quotes import (
    EXECUTABLE,
    LAUNCH_NODE,
    LAUNCH_PARAMETERS,
    LAUNCH_PERIOD,
    LAUNCH_PHILOSOPHER,
    LAUNCH_QUOTE,
    LAUNCH_TOPIC,
    PACKAGE,
    amazing_quote,
    package_source,
    quote_after,
    short,
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
    Check("load", "Loading the file into the running node (ros2 param load) sets its parameters", 2,
          "every parameter in the file must be accepted by the node (names and types as it declares them)",
          needs=FILE_OK),
    Check("observed_quote", f"After loading, /{LAUNCH_TOPIC} carries the file's quote and philosopher", 2,
          "the node must read quote and philosopher_name on every publish (parameters lesson)", needs=("load",)),
]


def grade(s: GradingSession) -> None:
    """Check the file, start the node as launched, load the file into it, watch for the new quote."""
    path, values = _read_file(s)
    _new_quote(s, values or {})  # judged on the file alone (needs node_key)
    probe = s.ros.topic(f"/{LAUNCH_TOPIC}", amazing_quote(s))
    proc = _start_node(s, probe)
    s.require("node_key")
    services = params.connect(s, LAUNCH_NODE, proc=proc)
    names = services.names()
    node = services.get(names)
    read_only = services.read_only(names)
    _check_types(s, values, node)
    expected = "every parameter set successfully (read-only ones like start_type_description_service excepted)"
    try:
        results = services.load(path, NODE_KEY)
    except ValueError as exc:
        s.record("load", False, f"rclpy (as ros2 param load) could not turn the file into parameters: {exc}", expected)
        return
    loaded_at = time.time()  # wall clock, as the send stamps the next messages are judged by
    failed = [r for r in results if not r.successful and not read_only.get(r.name, False)]
    quote_set = any(r.name == "quote" and r.successful for r in results)
    s.record("load", quote_set and not failed, "; ".join(r.line() for r in results) or "the file holds no parameters",
             expected)
    s.require("load")
    quote, philosopher = str(values.get("quote")), values.get("philosopher_name", LAUNCH_PHILOSOPHER)
    quote_after(s, "observed_quote", probe, loaded_at, count=NEXT_MESSAGES, period=LAUNCH_PERIOD, quote=quote,
                philosopher=philosopher, proc=proc, expected=f"within {NEXT_MESSAGES} messages after the load: "
                f"quote {short(quote)} and philosopher_name {philosopher!r}")
    with s.phase("stop"):
        proc.stop(sigint_timeout=3.0, sigterm_timeout=2.0)


def _read_file(s: GradingSession) -> tuple[Path, dict[str, Any] | None]:
    """``file_present``, ``yaml_valid``, ``node_key``; the path and the flat parameters (None: no node section).

    Raises:
        Unmet: no file, or not a YAML mapping.
    """
    import yaml  # noqa: PLC0415

    from course.lesson.catalog import yaml_error_text  # noqa: PLC0415

    source = package_source(s)
    path = source / CONFIG if source else None
    expected = f"src/{PACKAGE}/{CONFIG}"
    if path is None or not path.is_file():
        elsewhere = sorted(str(p.relative_to(s.workspace_root)) for p in (s.workspace_root / "src").rglob(
            f"*{LAUNCH_NODE}*.yaml")) if (s.workspace_root / "src").is_dir() else []
        observed = (f"no package {PACKAGE} in src/" if source is None else f"no file {CONFIG} in the package")
        s.record("file_present", False, observed + (f"; found {', '.join(elsewhere)}: move it to {expected}"
                                                    if elsewhere else ""), expected)
        raise Unmet("there is no parameters file to load")
    s.record("file_present", True, expected, expected)
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        s.record("yaml_valid", False, f"not valid YAML: {yaml_error_text(exc)}", "a YAML file ros2 param load can read")
        raise Unmet("the file is not valid YAML") from None
    if not isinstance(data, dict) or not data:
        shape = "empty (only comments?)" if data is None else f"a {type(data).__name__}, not a mapping"
        s.record("yaml_valid", False, f"the file is {shape}", "a YAML mapping: node name -> ros__parameters")
        raise Unmet("the file holds no parameters")
    s.record("yaml_valid", True, "valid YAML", "a YAML file ros2 param load can read")
    values, problem = params.dump_section(data, NODE_KEY)
    s.record("node_key", values is not None, problem or f"{NODE_KEY}: ros__parameters with {len(values)} entries",
             f"'{NODE_KEY}:' whose value has a 'ros__parameters:' mapping")
    return path, values


def _start_node(s: GradingSession, probe) -> Any:
    """Start the publisher as the launch file does; record ``node_running``; return the process.

    Raises:
        Unmet: no executable, no node, or no message on the topic.
    """
    action = NodeAction(line=0, package=PACKAGE, executable=EXECUTABLE, name=LAUNCH_NODE,
                        parameters=[dict(LAUNCH_PARAMETERS)])
    expected = (f"node /{LAUNCH_NODE} publishing the launch file's quote on /{LAUNCH_TOPIC} "
                f"(started like the launch-files lesson's launch file)")
    proc, reason = start_node_action(s, action, f"{EXECUTABLE}.as_launched")
    if proc is None:
        s.record("node_running", False, reason, expected)
        raise Unmet("the node could not be started")
    with s.phase("start"):
        found = s.ros.wait_for_node(LAUNCH_NODE, 10.0, abort=lambda: proc.poll() is not None)
        if found:
            probe.wait_for_count(1, timeout=3.0 + LATE_DELIVERY, abort=lambda: proc.poll() is not None)
    samples = probe.samples()
    if not found or not samples:
        seen = ", ".join(s.ros.node_names()) or "none"
        s.record("node_running", False, (f"no message on /{LAUNCH_TOPIC}; topics seen: {kit.topics_seen(s.ros)}"
                                         if found else f"no node {LAUNCH_NODE}; nodes seen: {seen}")
                 + f"; {kit.process_state(proc)}", expected)
        raise Unmet("the node is not running as the launch file would run it")
    first = samples[0][1]
    s.record("node_running", True, f"/{LAUNCH_NODE} publishes quote {short(first.quote, 40)} "
             f"by {first.philosopher_name!r} on /{LAUNCH_TOPIC}", expected)
    return proc


def _reparsed_type(text: str) -> str:
    """The type rclpy's ``get_parameter_value`` guesses for ``text`` (``ros2 param load`` re-parses values)."""
    import yaml  # noqa: PLC0415

    try:
        return params.python_type_name(yaml.safe_load(text))
    except yaml.YAMLError:
        return "string"


def _check_types(s: GradingSession, values: dict[str, Any], node: dict[str, tuple[str, Any]]) -> None:
    """``parameter_types``: every required parameter in the file, each one the node's, with the node's type."""
    expected = ("period, philosopher_name, quote and topic_name present; every parameter one the node declares, "
                "with its type (" + ", ".join(f"{n}: {node[n][0]}" for n in REQUIRED if n in node) + ")")
    problems = [f"{name} is missing" for name in REQUIRED if name not in values]
    for name, value in values.items():
        if name not in node:
            problems.append(f"the node has no parameter {name!r}")
            continue
        kind = params.python_type_name(value)
        if kind != node[name][0]:
            note = ""
            if isinstance(value, str) and _reparsed_type(value) == node[name][0]:
                note = (" (ros2 param load happens to re-read the text as a number, but --params-file and "
                        "launch files take it as a string: drop the quotes)")
            problems.append(f"{name} is a{'n' if kind[0] in 'aeiou' else ''} {kind} in the file "
                            f"({value!r}) but a {node[name][0]} in the node{note}")
    s.record("parameter_types", not problems,
             "; ".join(problems) if problems else f"{len(values)} parameters, names and types match the node's",
             expected)


def _new_quote(s: GradingSession, values: dict[str, Any]) -> None:
    """``new_quote``: the file's quote is not the launch file's (read from the file alone)."""
    quote = values.get("quote")
    expected = f"a quote different from the launch file's ({short(LAUNCH_QUOTE, 40)})"
    if not isinstance(quote, str):
        s.record("new_quote", False, "no quote string in the file" if quote is None else f"quote is {quote!r}",
                 expected)
    else:
        s.record("new_quote", quote.strip() != LAUNCH_QUOTE, f"quote: {short(quote)}"
                 + (" (the launch file's, unchanged)" if quote.strip() == LAUNCH_QUOTE else ""), expected)
