"""Kit steps for a running node's parameters, through its parameter services (what ``ros2 param`` uses).

``ros2 param list/get/describe/set/load`` (ros2param) talk to the node's
``list_parameters``, ``get_parameters``, ``describe_parameters`` and
``set_parameters`` services with rclpy's ``AsyncParameterClient``; so does
:class:`NodeParameters`, from the grader's own node in the session's private
graph. Every call that gets no answer raises :class:`ros2course.grade.checklist.Unmet`:
the checks that needed the answer become "not checked" with the reason.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

import yaml

from ros2course.grade.checklist import Unmet
from ros2course.kit.session_protocol import Session
from ros2course.lesson.catalog import yaml_error_text
from ros2course.run.probes import wait_future, wait_until
from ros2course.kit.launch import flatten_parameters
from ros2course.kit.nodes import process_state

#: rcl_interfaces/msg/ParameterType values -> the words ``ros2 param describe`` uses.
PARAMETER_TYPES = {0: "not set", 1: "boolean", 2: "integer", 3: "double", 4: "string", 5: "byte array",
                   6: "boolean array", 7: "integer array", 8: "double array", 9: "string array"}


def parameter_value(value_msg: Any) -> tuple[str, Any]:
    """``(type word, Python value)`` of an ``rcl_interfaces/msg/ParameterValue`` (words of :data:`PARAMETER_TYPES`)."""
    from rclpy.parameter import parameter_value_to_python  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)

    kind = PARAMETER_TYPES.get(value_msg.type, f"type {value_msg.type}")
    try:
        value = parameter_value_to_python(value_msg)
    except RuntimeError:
        value = None
    if isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
        value = list(value)
    return kind, value


def python_type_name(value: Any) -> str:
    """The ROS parameter type word a YAML/Python value maps to (as rclpy's ``Parameter`` infers it)."""
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "double"
    if isinstance(value, str):
        return "string"
    if isinstance(value, (list, tuple)):
        for word, kind in (("boolean", bool), ("integer", int), ("double", float), ("string", str)):
            if all(isinstance(v, kind) and (kind is bool or not isinstance(v, bool)) for v in value):
                return f"{word} array"
    return f"unsupported ({type(value).__name__})"


@dataclasses.dataclass(frozen=True)
class SetResult:
    """One parameter's answer to ``set_parameters`` (``ros2 param set/load`` print one line per parameter)."""

    name: str
    successful: bool
    reason: str

    def line(self) -> str:
        """``Set parameter NAME successful`` / ``... failed: REASON``, as ``ros2 param load`` prints it."""
        return (f"Set parameter {self.name} {'successful' if self.successful else 'failed'}"
                + (f": {self.reason}" if self.reason else ""))


class NodeParameters:
    """The parameter services of one running node (made by :func:`connect`).

    Every method waits ``timeout`` seconds for the answer and raises
    :class:`Unmet` when none comes.
    """

    def __init__(self, node: str, client: Any, timeout: float, proc: Any = None) -> None:
        self.node = node
        self._client = client
        self._timeout = timeout
        self._proc = proc

    def _answer(self, future: Any) -> Any:
        try:
            return wait_future(future, self._timeout)
        except TimeoutError as exc:
            state = f"; {process_state(self._proc)}" if self._proc is not None else ""
            raise Unmet(f"the parameter services of /{self.node} did not answer: {exc}{state}") from exc

    def names(self) -> list[str]:
        """``ros2 param list``: the names of the parameters the node declares."""
        return list(self._answer(self._client.list_parameters()).result.names)

    def get(self, names: list[str]) -> dict[str, tuple[str, Any]]:
        """``ros2 param get`` for each of ``names``: name -> (type word, value), in the order asked."""
        if not names:
            return {}
        values = self._answer(self._client.get_parameters(names)).values
        return {name: parameter_value(value) for name, value in zip(names, values)}

    def read_only(self, names: list[str]) -> dict[str, bool]:
        """``ros2 param describe``'s read-only flag for each of ``names``."""
        if not names:
            return {}
        descriptors = self._answer(self._client.describe_parameters(names)).descriptors
        return {name: bool(d.read_only) for name, d in zip(names, descriptors)}

    def set(self, values: dict[str, Any]) -> list[SetResult]:
        """``ros2 param set`` of every ``name: value`` in one (non-atomic) ``set_parameters`` call.

        The node applies the values before it answers, so a message sent after
        this returns was sent after the change.
        """
        from rclpy.parameter import Parameter  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)

        return self._set([Parameter(name, value=value).to_parameter_msg() for name, value in values.items()])

    def load(self, path: Path, node_key: str) -> list[SetResult]:
        """``ros2 param load /node PATH``: the file's parameters for ``node_key``, set in one non-atomic call.

        ros2param's ``load_parameter_file``: ``rclpy.parameter.parameter_dict_from_yaml_file``
        for that node (values re-parsed from their text, wildcards included),
        then ``set_parameters``.

        Raises:
            ValueError: rclpy cannot turn the file into parameters (message: its first line).
            Unmet: no answer.
        """
        from rclpy.parameter import parameter_dict_from_yaml_file  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)

        try:
            loaded = parameter_dict_from_yaml_file(str(path), target_nodes=[node_key])
        except (RuntimeError, TypeError, AttributeError, ValueError, yaml.YAMLError) as exc:
            text = str(exc).strip()
            raise ValueError(text.splitlines()[0] if text else type(exc).__name__) from exc
        return self._set(list(loaded.values()))

    def _set(self, messages: list[Any]) -> list[SetResult]:
        if not messages:
            return []
        response = self._answer(self._client.set_parameters(messages))
        return [SetResult(m.name, bool(r.successful), r.reason) for m, r in zip(messages, response.results)]


def connect(s: Session, node: str | None, *, proc: Any = None, why: str = "",
            timeout: float = 5.0) -> NodeParameters:
    """The parameter services of ``node`` (a node name without the leading ``/``) in ``s.graph``.

    Args:
        node: the node to ask (e.g. :attr:`ros2course.kit.StartedNode.name`); None: there is none.
        proc: its process, whose state is shown when the services do not answer.
        why: the reason there is no node, when ``node`` is None.
        timeout: seconds for the services to appear, then for each answer.

    Raises:
        Unmet: no node, or its services did not appear within ``timeout``.
    """
    if node is None:
        raise Unmet(f"no node to ask: {why}" if why else "no node to ask")
    from rclpy.parameter_client import AsyncParameterClient  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)

    # AsyncParameterClient has no destroy(); its clients go with the session's node.
    client = AsyncParameterClient(s.graph.node, node)
    if not wait_until(client.services_are_ready, timeout, interval=0.05):
        state = f"; {process_state(proc)}" if proc is not None else ""
        raise Unmet(f"the parameter services of /{node} did not appear within {timeout:.1f} s{state}")
    return NodeParameters(node, client, timeout, proc)


def dump_section(data: Any, node_key: str) -> tuple[dict[str, Any] | None, str]:
    """The parameters for ``node_key`` in a parsed ``ros2 param dump`` file, flattened to dotted names.

    The dump format (ros2param ``dump``: ``yaml.dump({"/node": {"ros__parameters": {...}}})``,
    shared/ROS_ENV.md) keys the parameters by the node's fully qualified name.

    Args:
        data: what ``yaml.safe_load`` returned (a non-empty mapping).
        node_key: the fully qualified node name, e.g. ``"/my_node"``.

    Returns:
        ``(parameters, "")``, or ``(None, what is wrong)`` in the learner's terms.
    """

    if node_key not in data:
        note = ""
        if node_key.lstrip("/") in data:
            note = " (ros2 param dump writes the fully qualified name, with the leading /)"
        elif "/**" in data:
            note = " ('/**' only loads with --use-wildcard; the dump format names the node)"
        return None, f"top-level keys: {', '.join(repr(k) for k in data) or 'none'}{note}"
    section = data[node_key]
    if not isinstance(section, dict) or "ros__parameters" not in section:
        inner = ", ".join(repr(k) for k in section) if isinstance(section, dict) else repr(section)
        return None, f"{node_key} holds {inner or 'nothing'}, no ros__parameters"
    found = section["ros__parameters"]
    if not isinstance(found, dict) or not found:
        return None, f"{node_key}: ros__parameters is {found!r}, not a mapping of parameters"
    return flatten_parameters(found), ""


# --- steps over a parameters file and a node's declared parameters -----------------------------

def read_dump(s: Session, present_id: str, valid_id: str, key_id: str, path: Path | None, node_key: str, *,
              shown: str, absent: str, search: Path, pattern: str) -> dict[str, Any] | None:
    """Record ``present_id`` (``path`` is a file), ``valid_id`` (YAML mapping) and ``key_id`` (:func:`dump_section`).

    Args:
        path: where the file must be (None: its folder does not exist).
        shown: how the learner names that place, e.g. ``src/pkg/config/node.yaml``.
        absent: observed text when ``path`` is None (e.g. "no package pkg in src/").
        search: a folder searched for misplaced copies (files matching the glob ``pattern``).

    Returns:
        The node's flat parameters, or None when ``key_id`` failed.

    Raises:
        Unmet: no file, not valid YAML, or not a non-empty mapping.
    """


    if path is None or not path.is_file():
        root = s.workspace_root
        elsewhere = sorted(str(p.relative_to(root)) for p in search.rglob(pattern)) if search.is_dir() else []
        s.record(present_id, False, (absent if path is None else f"no file {shown}")
                 + (f"; found {', '.join(elsewhere)}: move it to {shown}" if elsewhere else ""), shown)
        raise Unmet("there is no parameters file to load")
    s.record(present_id, True, shown, shown)
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        s.record(valid_id, False, f"not valid YAML: {yaml_error_text(exc)}", "a YAML file ros2 param load can read")
        raise Unmet("the file is not valid YAML") from None
    if not isinstance(data, dict) or not data:
        shape = "empty (only comments?)" if data is None else f"a {type(data).__name__}, not a mapping"
        s.record(valid_id, False, f"the file is {shape}", "a YAML mapping: node name -> ros__parameters")
        raise Unmet("the file holds no parameters")
    s.record(valid_id, True, "valid YAML", "a YAML file ros2 param load can read")
    values, problem = dump_section(data, node_key)
    s.record(key_id, values is not None, problem or f"{node_key}: ros__parameters with {len(values)} entries",
             f"'{node_key}:' whose value has a 'ros__parameters:' mapping")
    return values


def _reparsed_type(text: str) -> str:
    """The type rclpy's ``get_parameter_value`` guesses for ``text`` (``ros2 param load`` re-parses values)."""

    try:
        return python_type_name(yaml.safe_load(text))
    except yaml.YAMLError:
        return "string"


def file_types(s: Session, check_id: str, values: dict[str, Any], node: dict[str, tuple[str, Any]],
               required: tuple[str, ...]) -> bool:
    """Record ``check_id``: the file's ``values`` hold every ``required`` name, each one the node declares
    (``node``: :meth:`NodeParameters.get` of all its names), with the node's type.

    A quoted number is named as such: ``ros2 param load`` happens to re-read it
    as a number, but ``--params-file`` and launch files take it as a string.
    """
    expected = (f"{', '.join(required)} present; every parameter one the node declares, with its type ("
                + ", ".join(f"{n}: {node[n][0]}" for n in required if n in node) + ")")
    problems = [f"{name} is missing" for name in required if name not in values]
    for name, value in values.items():
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
    return s.record(check_id, not problems,
                    "; ".join(problems) if problems else f"{len(values)} parameters, names and types match the node's",
                    expected)


def load_file(s: Session, check_id: str, services: NodeParameters, path: Path, node_key: str, *,
              must_set: str) -> float:
    """``ros2 param load`` ``path`` into the node; record ``check_id``: every parameter set (read-only ones
    like ``start_type_description_service`` excepted) and ``must_set`` among them.

    Returns:
        When the load was answered (``time.time()`` seconds: messages sent later carry the values).

    Raises:
        Unmet: rclpy cannot read the file, or ``check_id`` failed (``s.require``).
    """

    read_only = services.read_only(services.names())
    expected = "every parameter set successfully (read-only ones like start_type_description_service excepted)"
    try:
        results = services.load(path, node_key)
    except ValueError as exc:
        s.record(check_id, False, f"rclpy (as ros2 param load) could not turn the file into parameters: {exc}",
                 expected)
        raise Unmet("the file could not be loaded") from exc
    loaded_at = time.time()
    failed = [r for r in results if not r.successful and not read_only.get(r.name, False)]
    done = any(r.name == must_set and r.successful for r in results)
    s.record(check_id, done and not failed, "; ".join(r.line() for r in results) or "the file holds no parameters",
             expected)
    s.require(check_id)
    return loaded_at


def declared(s: Session, declared_id: str, defaults_id: str, services: NodeParameters,
             defaults: dict[str, Any]) -> None:
    """Record ``declared_id`` (``ros2 param list`` has every name of ``defaults``) and ``defaults_id``
    (``ros2 param get`` of each gives its default, a float as a double and a str as a string).
    Partial credit per parameter for ``defaults_id``.
    """
    names = services.names()
    missing = [name for name in defaults if name not in names]
    s.record(declared_id, not missing, "declared parameters: " + (", ".join(sorted(names)) or "none")
             + (f"; missing: {', '.join(missing)}" if missing else ""), f"{', '.join(defaults)} among them")
    values = services.get([name for name in defaults if name in names])
    wrong = [f"{name} = {value!r} ({kind})" for name, (kind, value) in values.items()
             if (kind, value) != (python_type_name(defaults[name]), defaults[name])]
    wrong += [f"{name} not declared" for name in missing]
    shown = ", ".join(f"{name} = {value!r} ({python_type_name(value)})" for name, value in defaults.items())
    s.record(defaults_id, not wrong, f"all {len(defaults)} as expected" if not wrong else
             f"none of the {len(defaults)} parameters is declared" if not values else "; ".join(wrong), shown,
             fraction=(len(values) - len(wrong) + len(missing)) / len(defaults))


#: Seconds for a node's parameter services to appear, then to answer (:func:`record_spins`).
SPIN_TIMEOUT = 5.0
#: Seconds between the timed calls of :func:`record_spins`: irregular, so no loop's period can meet them in step.
SPIN_GAPS = (0.23, 0.31, 0.17, 0.37, 0.26, 0.13, 0.34, 0.21, 0.29)
#: Median seconds a spinning node may take to answer: an executor serves a call at once (a few ms; tens under
#: load), a loop that spins once between sleeps of ``p`` seconds answers after ``p / 2`` on average.
SPIN_LATENCY = 0.15


def record_spins(s: Session, check_id: str, started: Any) -> bool:
    """Record ``check_id`` (declared with :func:`ros2course.kit.checks.spins`): the running node
    (a :class:`~ros2course.kit.nodes.StartedNode`) answers ``list_parameters`` (what ``ros2 param list`` calls)
    within :data:`SPIN_TIMEOUT` seconds, and answers it at once: of one call after each of the irregular pauses
    :data:`SPIN_GAPS`, the median answer comes within :data:`SPIN_LATENCY` s.

    Every rclpy and rclcpp node offers its parameter services; the executor that spins
    the node serves them. A node whose process never spins (a ``while`` loop with
    ``time.sleep`` instead of a timer, seed ch. 13.3) has the services but never answers; one
    that spins once between two sleeps (``rclpy.spin_once(node, timeout_sec=0)`` then
    ``time.sleep(0.5)``, the ROS 1 habit) answers only between sleeps, about a quarter of a second
    late: the lesson's "would block spin and starve every other callback" (helper audit of issue 37).
    """
    expected = (f"/{started.name or '<your node>'} answers list_parameters within {SPIN_TIMEOUT:.0f} s, and at "
                f"once: the median of {len(SPIN_GAPS)} answers within {SPIN_LATENCY * 1000:.0f} ms")
    try:
        services = connect(s, started.name, proc=started.proc, why="no node of yours appeared",
                           timeout=SPIN_TIMEOUT)
        names = services.names()
        latencies = []
        for gap in SPIN_GAPS:
            if started.proc.poll() is not None:
                break
            time.sleep(gap)
            begin = time.monotonic()
            services.names()
            latencies.append(time.monotonic() - begin)
    except Unmet as exc:
        return s.record(check_id, False, f"{exc}: the node does not spin", expected)
    if not latencies:
        return s.record(check_id, False, f"/{started.name} answered once, then ended: "
                        f"{process_state(started.proc)}", expected)
    median = sorted(latencies)[len(latencies) // 2]
    return s.record(check_id, median <= SPIN_LATENCY,
                    f"/{started.name} answered with {len(names)} parameter name(s), in {median * 1000:.0f} ms "
                    f"(median of {len(latencies)} calls; slowest {max(latencies) * 1000:.0f} ms)"
                    + ("" if median <= SPIN_LATENCY else ": it serves calls only now and then (a loop that "
                       "sleeps between spins?)"), expected)
