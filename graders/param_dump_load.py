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
   (``rclpy.parameter.parameter_dict_from_yaml_file`` for this node, then one
   non-atomic ``set_parameters`` call, results reported per parameter);
5. watches ``/truly_inspirational_quote`` for the new quote.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from course.grading import Check, GradingSession
from course.probes import LATE_DELIVERY, parameter_client, wait_future
from graders._common import process_state
from graders.kit.launch import NodeAction, flatten_parameters, start_node_action
from graders.kit.quotes import (EXECUTABLE, LAUNCH_NODE, LAUNCH_PARAMETERS, LAUNCH_PERIOD, LAUNCH_PHILOSOPHER,
                             LAUNCH_QUOTE, LAUNCH_TOPIC, PACKAGE, amazing_quote, package_source, parameter_value,
                             python_type_name, short, topics_seen)

CONFIG = Path("config") / f"{LAUNCH_NODE}.yaml"  # inside the package's source folder
NODE_KEY = f"/{LAUNCH_NODE}"
#: The parameters the configurable publisher declares (parameters lesson); the file must hold them all.
REQUIRED = ("period", "philosopher_name", "quote", "topic_name")
#: A loaded quote must show within this many messages (one may be on its way: seed ch. 24.5).
NEXT_MESSAGES = 3

#: Seconds of observation the contract needs: the loaded quote in the next messages at 4 Hz.
WINDOW = (NEXT_MESSAGES + 1) * LAUNCH_PERIOD

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("file_present", f"The parameters file is at src/{PACKAGE}/{CONFIG}", 1,
          f"save the dump as src/{PACKAGE}/{CONFIG}"),
    Check("yaml_valid", "The file is valid YAML", 1,
          "quote strings that contain ': ' or start with a quote character, and keep the indentation consistent"),
    Check("node_key", f"Its top-level key is {NODE_KEY} with a ros__parameters mapping (the dump format)", 2,
          f"the file starts with '{NODE_KEY}:', then '  ros__parameters:', then the parameters indented below it"),
    Check("node_running", f"The node starts as the launch file starts it and publishes on /{LAUNCH_TOPIC}", 1,
          "the launch-files lesson's node must work first: run its check"),
    Check("parameter_types", "The file's parameters are the node's, with the node's types", 2,
          "period must stay a float (0.25, not '0.25' or 1); strings stay strings; only parameters the node has"),
    Check("new_quote", "The file's quote is a new one (not the launch file's)", 1,
          "edit the quote: value in the file"),
    Check("load", "Loading the file into the running node (ros2 param load) sets its parameters", 2,
          "every parameter in the file must be accepted by the node (names and types as it declares them)"),
    Check("observed_quote", f"After loading, /{LAUNCH_TOPIC} carries the file's quote and philosopher", 2,
          "the node must read quote and philosopher_name on every publish (parameters lesson)"),
]


def _read_file(s: GradingSession) -> tuple[Path | None, dict[str, Any] | None]:
    """``file_present``, ``yaml_valid``, ``node_key``; returns the path and the flat parameters (or None)."""
    import yaml  # noqa: PLC0415

    from course.lesson import yaml_error_text  # noqa: PLC0415

    source = package_source(s)
    path = source / CONFIG if source else None
    expected = f"src/{PACKAGE}/{CONFIG}"
    if path is None or not path.is_file():
        elsewhere = sorted(str(p.relative_to(s.workspace_root)) for p in (s.workspace_root / "src").rglob(
            f"*{LAUNCH_NODE}*.yaml")) if (s.workspace_root / "src").is_dir() else []
        observed = (f"no package {PACKAGE} in src/" if source is None else f"no file {CONFIG} in the package")
        if elsewhere:
            observed += f"; found {', '.join(elsewhere)}: move it to {expected}"
        s.record("file_present", False, observed, expected)
        s.skip_remaining("there is no parameters file to load")
        return None, None
    s.record("file_present", True, expected, expected)
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        s.record("yaml_valid", False, f"not valid YAML: {yaml_error_text(exc)}", "a YAML file ros2 param load can read")
        s.skip_remaining("the file is not valid YAML")
        return path, None
    if not isinstance(data, dict) or not data:
        shape = "empty (only comments?)" if data is None else f"a {type(data).__name__}, not a mapping"
        s.record("yaml_valid", False, f"the file is {shape}", "a YAML mapping: node name -> ros__parameters")
        s.skip_remaining("the file holds no parameters")
        return path, None
    s.record("yaml_valid", True, "valid YAML", "a YAML file ros2 param load can read")
    keys = ", ".join(repr(k) for k in data) or "none"
    expected_key = f"'{NODE_KEY}:' whose value has a 'ros__parameters:' mapping"
    if NODE_KEY not in data:
        note = ""
        if LAUNCH_NODE in data:
            note = " (ros2 param dump writes the fully qualified name, with the leading /)"
        elif "/**" in data:
            note = " ('/**' only loads with --use-wildcard; the dump format names the node)"
        s.record("node_key", False, f"top-level keys: {keys}{note}", expected_key)
        return path, None
    section = data[NODE_KEY]
    if not isinstance(section, dict) or "ros__parameters" not in section:
        inner = ", ".join(repr(k) for k in section) if isinstance(section, dict) else repr(section)
        s.record("node_key", False, f"{NODE_KEY} holds {inner or 'nothing'}, no ros__parameters", expected_key)
        return path, None
    params = section["ros__parameters"]
    if not isinstance(params, dict) or not params:
        s.record("node_key", False, f"{NODE_KEY}: ros__parameters is {params!r}, not a mapping of parameters",
                 expected_key)
        return path, None
    s.record("node_key", True, f"{NODE_KEY}: ros__parameters with {len(params)} entries", expected_key)
    return path, flatten_parameters(params)


def _start_node(s: GradingSession, probe) -> Any | None:
    """Start the publisher as the launch file does; record ``node_running``; return the process or None."""
    action = NodeAction(line=0, package=PACKAGE, executable=EXECUTABLE, name=LAUNCH_NODE,
                        parameters=[dict(LAUNCH_PARAMETERS)])
    expected = (f"node /{LAUNCH_NODE} publishing the launch file's quote on /{LAUNCH_TOPIC} "
                f"(started like the launch-files lesson's launch file)")
    proc, reason = start_node_action(s, action, f"{EXECUTABLE}.as_launched")
    if proc is None:
        s.record("node_running", False, reason, expected)
        s.skip_remaining("the node could not be started")
        return None
    with s.phase("start"):
        found = s.ros.wait_for_node(LAUNCH_NODE, 10.0, abort=lambda: proc.poll() is not None)
        if found:
            probe.wait_for_count(1, timeout=3.0 + LATE_DELIVERY, abort=lambda: proc.poll() is not None)
    samples = probe.samples()
    if not found or not samples:
        seen = ", ".join(s.ros.node_names()) or "none"
        s.record("node_running", False, (f"no message on /{LAUNCH_TOPIC}; topics seen: {topics_seen(s)}" if found else
                                         f"no node {LAUNCH_NODE}; nodes seen: {seen}") + f"; {process_state(proc)}",
                 expected)
        s.skip_remaining("the node is not running as the launch file would run it")
        return None
    first = samples[0][1]
    s.record("node_running", True, f"/{LAUNCH_NODE} publishes quote {short(first.quote, 40)} "
             f"by {first.philosopher_name!r} on /{LAUNCH_TOPIC}", expected)
    return proc


def _reparsed_type(text: str) -> str:
    """The type rclpy's ``get_parameter_value`` guesses for ``text`` (``ros2 param load`` re-parses values)."""
    import yaml  # noqa: PLC0415

    try:
        return python_type_name(yaml.safe_load(text))
    except yaml.YAMLError:
        return "string"


def _node_parameters(client) -> dict[str, tuple[str, Any, bool]]:
    """The running node's parameters: name -> (type word, value, read_only)."""
    names = list(wait_future(client.list_parameters(), 5.0).result.names)
    if not names:
        return {}
    values = wait_future(client.get_parameters(names), 5.0).values
    descriptors = wait_future(client.describe_parameters(names), 5.0).descriptors
    out = {}
    for name, value_msg, descriptor in zip(names, values, descriptors):
        kind, value = parameter_value(value_msg)
        out[name] = (kind, value, bool(descriptor.read_only))
    return out


def _check_types(s: GradingSession, params: dict[str, Any] | None, node: dict[str, tuple[str, Any, bool]]) -> None:
    """``parameter_types`` and ``new_quote``."""
    expected = ("period, philosopher_name, quote and topic_name present; every parameter one the node declares, "
                "with its type (" + ", ".join(f"{n}: {node[n][0]}" for n in REQUIRED if n in node) + ")")
    if params is None:
        s.record("parameter_types", False, "not checked: the file has no ros__parameters for the node", expected)
        s.record("new_quote", False, "not checked: the file has no ros__parameters for the node",
                 "a quote different from the launch file's")
        return
    problems = [f"{name} is missing" for name in REQUIRED if name not in params]
    for name, value in params.items():
        if name not in node:
            problems.append(f"the node has no parameter {name!r}")
            continue
        kind = python_type_name(value)
        if kind != node[name][0]:
            note = ""
            if isinstance(value, str) and _reparsed_type(value) == node[name][0]:
                note = (" (ros2 param load happens to re-read the text as a number, but --params-file and "
                        "launch files take it as a string: drop the quotes)")
            problems.append(f"{name} is a{'n' if kind[0] in 'aeiou' else ''} {kind} in the file "
                            f"({value!r}) but a {node[name][0]} in the node{note}")
    s.record("parameter_types", not problems,
             "; ".join(problems) if problems else f"{len(params)} parameters, names and types match the node's",
             expected)
    quote = params.get("quote")
    expected_quote = f"a quote different from the launch file's ({short(LAUNCH_QUOTE, 40)})"
    if not isinstance(quote, str):
        s.record("new_quote", False, "no quote string in the file" if quote is None else f"quote is {quote!r}",
                 expected_quote)
    else:
        s.record("new_quote", quote.strip() != LAUNCH_QUOTE, f"quote: {short(quote)}"
                 + (" (the launch file's, unchanged)" if quote.strip() == LAUNCH_QUOTE else ""), expected_quote)


def _load(s: GradingSession, client, path: Path, params: dict[str, Any] | None,
          node: dict[str, tuple[str, Any, bool]]) -> float | None:
    """``load``: ``ros2 param load`` for this node; returns the wall-clock time (time.time() s) the answer came, or None."""
    from rclpy.parameter import parameter_dict_from_yaml_file  # noqa: PLC0415

    expected = "every parameter set successfully (read-only ones like start_type_description_service excepted)"
    if params is None:
        s.record("load", False, f"not loaded: the file has no {NODE_KEY} ros__parameters section", expected)
        return None
    import yaml  # noqa: PLC0415

    try:
        loaded = parameter_dict_from_yaml_file(str(path), target_nodes=[NODE_KEY])
    except (RuntimeError, TypeError, AttributeError, ValueError, yaml.YAMLError) as exc:
        first_line = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        s.record("load", False, f"rclpy (as ros2 param load) could not turn the file into parameters: {first_line}",
                 expected)
        return None
    messages = list(loaded.values())
    response = wait_future(client.set_parameters(messages), 5.0)
    done = time.time()  # wall clock, as the send stamps the next messages are judged by
    lines, failed = [], []
    for message, result in zip(messages, response.results):
        text = f"Set parameter {message.name} {'successful' if result.successful else 'failed'}"
        if result.reason:
            text += f": {result.reason}"
        lines.append(text)
        read_only = node.get(message.name, ("", None, False))[2]
        if not result.successful and not read_only:
            failed.append(message.name)
    quote_set = any(m.name == "quote" and r.successful for m, r in zip(messages, response.results))
    passed = quote_set and not failed
    s.record("load", passed, "; ".join(lines) or "the file holds no parameters", expected)
    return done


def _observe(s: GradingSession, probe, proc, params: dict[str, Any] | None, loaded_at: float | None) -> None:
    """``observed_quote``: the next messages after the load carry the file's quote and philosopher."""
    quote = params.get("quote") if params else None
    philosopher = params.get("philosopher_name", LAUNCH_PHILOSOPHER) if params else LAUNCH_PHILOSOPHER
    expected = (f"within {NEXT_MESSAGES} messages after the load: quote {short(str(quote))} "
                f"and philosopher_name {philosopher!r}")
    if loaded_at is None or not isinstance(quote, str):
        s.record("observed_quote", False, "not checked: nothing was loaded", expected)
        return

    with s.phase("observe"):
        later = probe.wait_sent_after(loaded_at, NEXT_MESSAGES, LAUNCH_PERIOD, abort=lambda: proc.poll() is not None)
    if not later:
        s.record("observed_quote", False, f"no message on /{LAUNCH_TOPIC} after the load; {process_state(proc)}",
                 expected)
        return
    last = later[min(NEXT_MESSAGES, len(later)) - 1]
    quote_ok = last.quote == quote
    name_ok = last.philosopher_name == philosopher
    seen = ", ".join(f"({short(m.quote, 30)}, {m.philosopher_name!r})" for m in later[:NEXT_MESSAGES])
    s.record("observed_quote", quote_ok and name_ok, f"the next {len(later[:NEXT_MESSAGES])} message(s): {seen}",
             expected, fraction=(quote_ok + name_ok) / 2)


def grade(s: GradingSession) -> None:
    """Check the file, start the node as launched, load the file into it, watch for the new quote."""
    path, params = _read_file(s)
    if path is None or "yaml_valid" not in s.results or not s.results["yaml_valid"].passed:
        return
    probe = s.ros.topic(f"/{LAUNCH_TOPIC}", amazing_quote(s))
    proc = _start_node(s, probe)
    if proc is None:
        return
    try:
        with parameter_client(s.ros, LAUNCH_NODE, timeout=5.0) as client:
            node = _node_parameters(client)
            _check_types(s, params, node)
            loaded_at = _load(s, client, path, params, node)
            _observe(s, probe, proc, params, loaded_at)
    except TimeoutError as exc:
        s.skip_remaining(f"the parameter services of /{LAUNCH_NODE} did not answer: {exc}")
    with s.phase("stop"):
        proc.stop(sigint_timeout=3.0, sigterm_timeout=2.0)
