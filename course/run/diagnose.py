"""Why "nothing arrived": a diagnosis of the graph when a check that watched it fails (issue 19).

A lesson may declare the graph its contract expects (``graph:`` in its
``lesson.yaml``: :class:`ros2course.lesson.catalog.LessonGraph`). When a check
that watched a graph fails, the engine (:meth:`ros2course.grade.session.GradingSession.record`)
calls :func:`diagnose` once per part and attaches what it finds to the check.
Each finding is a :class:`Diagnosis` of one of these kinds, and where its rule
comes from:

* ``near_name``: an expected node, topic or service is absent and a name a few
  characters away, or the same name in another namespace, is there (the
  nearest names by :mod:`difflib`'s ratio, as ``ros2`` suggests a close
  verb; the distance in characters is the Levenshtein distance). Names are
  the graph's own fully qualified names (``Node.get_node_names_and_namespaces``,
  ``get_publisher_names_and_types_by_node`` and the others ``ros2 node info``
  uses), so a missing or extra leading slash shows as a namespace difference;
* ``other_type``: the expected name is there with another type (both named;
  the types ``ros2 topic info`` / ``ros2 node info`` show: endpoints of two
  types on one name never connect);
* ``qos``: a learner's endpoint and the grader's (or another learner's) on an
  expected topic cannot match, judged by ``rclpy.qos.qos_check_compatible(publisher_qos,
  subscription_qos)`` on the profiles ``Node.get_publishers_info_by_topic`` and
  ``get_subscriptions_info_by_topic`` report (both profiles named);
* ``no_peer``: no learner node publishes (subscribes to, serves, calls) the
  expected name at all (``ros2 doctor``'s "publisher without subscriber" check,
  seen from the grader's side);
* ``duplicate_node``: two or more nodes of the graph share one fully
  qualified name (``ros2 node list`` warns of it: their parameters and
  services are then ambiguous). A node stopped a moment ago can linger in the
  graph until its participant's lease expires, so a grader that restarts a
  node in one graph may see it twice for a while;
* ``process``: a learner process of the part ended before the grader stopped
  it: exit code and seconds after start, or the signal that killed it, with
  its last traceback line or ERROR/FATAL log line
  (:meth:`~ros2course.run.process.LearnerProcess.exit_state`, the account
  ``kit.process_state`` also prints); and, for a console script of an
  ``ament_python`` package, an entry point missing from the installed
  metadata that the script loads (setuptools' generated script looks its
  entry point up with ``importlib.metadata.distribution(name).entry_points``:
  the first ``*.egg-info``/``*.dist-info`` of that name on its path wins);
* ``silent``: the learner's node has the expected publisher (the graph shows
  it with the contract's type) and a grader's probe on that topic has had a
  matched publisher (rmw's ``matched`` event: same type, compatible QoS) for
  at least :data:`SILENT_AFTER` seconds, yet nothing arrived since the match
  (:func:`silent_topics`): a node that never spins, a timer never created.
  Only then is it said, and only when nothing else explains the failure.

A node missing without any near name is not reported (the check's own
observed text lists the nodes seen).

Bounds: at most :data:`MAX_FINDINGS` findings, :data:`MAX_NODES` nodes
inspected, names cut to :data:`NAME_CHARS` characters with control and
non-printable characters escaped. :func:`diagnose` never raises: a failed
graph query is logged at debug level and its findings dropped. Nothing here
changes a verdict or a score. Cost: a few in-process rcl graph queries (no
waiting, no DDS traffic), milliseconds per failed check.
"""

from __future__ import annotations

import collections
import dataclasses
import difflib
import logging
import re
import time
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the lesson model and the process are only types here
    from ros2course.lesson.catalog import LessonGraph
    from ros2course.run.process import LearnerProcess

LOG = logging.getLogger(__name__)

#: Findings kept per diagnosis (the first ones, in the order of the contract's entries).
MAX_FINDINGS = 6
#: Learner nodes inspected per diagnosis (each costs four graph queries).
MAX_NODES = 20
#: Characters kept of a name taken from the graph (a learner's node can name anything).
NAME_CHARS = 80
#: Near names shown per expected name.
MAX_NEAR = 2
#: difflib ratio from which a name counts as near (``difflib.get_close_matches``' default).
NEAR_CUTOFF = 0.6
#: Seconds a grader's subscription must have matched the learner's publisher, with nothing received,
#: before ``silent`` is said: four periods of the course's slowest contract timer (0.5 s), and well past
#: the few milliseconds endpoint discovery takes once both participants know each other.
SILENT_AFTER = 2.0
KINDS = ("process", "near_name", "other_type", "qos", "no_peer", "duplicate_node", "silent")

#: Endpoints every rclpy/rclcpp node has: never the learner's own.
_STANDARD_TOPICS = frozenset({"/rosout", "/parameter_events"})
_STANDARD_SERVICE_SUFFIXES = ("/describe_parameters", "/get_parameter_types", "/get_parameters",
                              "/list_parameters", "/set_parameters", "/set_parameters_atomically",
                              "/get_type_description")
_VERB = {"publish": "publishes", "subscribe": "subscribes to", "serve": "serves", "call": "calls"}


@dataclasses.dataclass(frozen=True)
class Diagnosis:
    """One finding about the graph, shown under a failed check as ``why: <message>``.

    Attributes:
        kind: one of :data:`KINDS`.
        message: one sentence for the learner, naming what was expected and what is there.
        detail: the names involved, e.g. ``{"expected": "/amazing_quote", "found": "/amazing_quotes",
            "node": "/amazing_quote_publisher_node", "type": "package_with_interfaces/msg/AmazingQuote"}``.
    """

    kind: str
    message: str
    detail: dict[str, str] = dataclasses.field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """``{"kind", "message", "detail"}`` (JSON)."""
        return {"kind": self.kind, "message": self.message, "detail": dict(self.detail)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Diagnosis:
        """The inverse of :meth:`to_dict` (missing keys empty)."""
        detail = data.get("detail")
        return cls(str(data.get("kind", "")), str(data.get("message", "")),
                   {str(k): str(v) for k, v in detail.items()} if isinstance(detail, dict) else {})

    def mentions(self, word: str) -> bool:
        """True when ``word`` occurs (case-insensitively) in the message or a detail value."""
        word = word.lower()
        return word in self.message.lower() or any(word in v.lower() for v in self.detail.values())


def clean(name: str) -> str:
    """``name`` safe to print: non-printable characters escaped, cut to :data:`NAME_CHARS` characters."""
    text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(name))
    return text if len(text) <= NAME_CHARS else text[:NAME_CHARS - 1] + "…"


def edit_distance(a: str, b: str) -> int:
    """Levenshtein distance: characters inserted, deleted or replaced to turn ``a`` into ``b``."""
    previous = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        current = [i]
        for j, cb in enumerate(b, 1):
            current.append(min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (ca != cb)))
        previous = current
    return previous[-1]


def _split(name: str) -> tuple[str, str]:
    """``/ns/base`` -> ``("/ns", "base")``; ``/base`` -> ``("/", "base")``."""
    namespace, _, base = name.rpartition("/")
    return namespace or "/", base


def how_near(expected: str, found: str) -> str:
    """How ``found`` differs from ``expected``: ``"one character from /x"``, ``"in namespace /ns, not /"``."""
    exp_ns, exp_base = _split(expected)
    got_ns, got_base = _split(found)
    if exp_base == got_base and exp_ns != got_ns:
        return f"the same name in namespace {clean(got_ns)}, not {clean(exp_ns)}"
    distance = edit_distance(expected, found)
    count = "one character" if distance == 1 else f"{distance} characters"
    return f"{count} from {clean(expected)}"


def near_names(expected: str, candidates: list[str]) -> list[str]:
    """The names of ``candidates`` nearest to ``expected``, nearest first (at most :data:`MAX_NEAR`).

    Near means the same last segment in another namespace, or a :mod:`difflib`
    ratio of at least :data:`NEAR_CUTOFF` on the whole name or on its last segment.
    """
    others = [c for c in dict.fromkeys(candidates) if c != expected]
    base = _split(expected)[1]
    same_base = [c for c in others if _split(c)[1] == base]
    close = difflib.get_close_matches(expected, others, n=MAX_NEAR, cutoff=NEAR_CUTOFF)
    by_base = {_split(c)[1]: c for c in others}
    close += [by_base[b] for b in difflib.get_close_matches(base, list(by_base), n=MAX_NEAR, cutoff=NEAR_CUTOFF)]
    return list(dict.fromkeys(same_base + close))[:MAX_NEAR]


def short_type(type_name: str) -> str:
    """``pkg/msg/AmazingQuote`` -> ``AmazingQuote``."""
    return clean(type_name.rsplit("/", 1)[-1])


def describe_qos(profile: Any) -> str:
    """A QoS profile in ``ros2 topic info -v``'s terms: ``RELIABLE, VOLATILE`` (``, KEEP_LAST (1)`` when known).

    The graph reports the policies that decide matching (reliability, durability, ...); the
    history of a remote endpoint is ``UNKNOWN`` there, so it is left out then.
    """
    def word(policy: Any) -> str:
        return str(getattr(policy, "name", policy)).upper()

    history = word(profile.history)
    depth = f", {history} ({profile.depth})" if history == "KEEP_LAST" else ""
    return f"{word(profile.reliability)}, {word(profile.durability)}{depth}"


@dataclasses.dataclass
class GraphSnapshot:
    """What the graph shows at one moment: the learner's nodes and their own endpoints.

    Attributes:
        names: fully qualified names of every non-hidden node (duplicates kept).
        ends: ``role -> name -> node -> type names``; roles ``publish``, ``subscribe``
            (topics), ``serve``, ``call`` (services), as ``ros2 node info`` lists them;
            ROS's own (``/rosout``, ``/parameter_events``, parameter services) left out.
    """

    names: list[str]
    ends: dict[str, dict[str, dict[str, list[str]]]]

    def to_dict(self) -> dict[str, Any]:
        """The JSON shape of ``graph.json`` (``{"nodes": [...], "ends": {...}}``)."""
        return {"nodes": list(self.names), "ends": self.ends}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> GraphSnapshot:
        """Inverse of :meth:`to_dict`."""
        ends = data.get("ends") or {}
        return cls([str(n) for n in data.get("nodes", [])],
                   {role: {str(name): {str(node): [str(t) for t in types] for node, types in by_node.items()}
                           for name, by_node in (ends.get(role) or {}).items()}
                    for role in ("publish", "subscribe", "serve", "call")})


def snapshot(ros: Any) -> GraphSnapshot | None:
    """The learner's nodes and endpoints in the graph of ``ros`` (an entered RosSession) right now.

    For ``ros2course graph`` (the observed side, kept in the check's ``graph.json``). Never
    raises: a failed query gives None (logged at debug level). Cost: four rcl graph queries
    per node (no waiting, no DDS traffic), at most :data:`MAX_NODES` nodes.
    """
    try:
        return _snapshot(ros.node)
    except Exception:  # noqa: BLE001 - advice only
        LOG.debug("graph snapshot failed", exc_info=True)
        return None


def _snapshot(ros_node: Any) -> GraphSnapshot:
    """Query the graph through ``ros_node`` (an rclpy ``Node``): the learner's nodes and their endpoints."""
    names = []
    pairs = []
    for name, namespace in ros_node.get_node_names_and_namespaces():
        if name.startswith("_"):  # hidden: the grader's own nodes, ros2cli's daemon
            continue
        names.append(f"{namespace.rstrip('/')}/{name}")
        pairs.append((name, namespace))
    queries = {"publish": ros_node.get_publisher_names_and_types_by_node,
               "subscribe": ros_node.get_subscriber_names_and_types_by_node,
               "serve": ros_node.get_service_names_and_types_by_node,
               "call": ros_node.get_client_names_and_types_by_node}
    ends: dict[str, dict[str, dict[str, list[str]]]] = {role: {} for role in queries}
    for name, namespace in list(dict.fromkeys(pairs))[:MAX_NODES]:
        node = f"{namespace.rstrip('/')}/{name}"
        for role, query in queries.items():
            try:
                found = query(name, namespace)
            except Exception:  # noqa: BLE001 - the node left the graph meanwhile
                LOG.debug("graph query %s of %s failed", role, node, exc_info=True)
                continue
            for end, types in found:
                if end in _STANDARD_TOPICS or end.endswith(_STANDARD_SERVICE_SUFFIXES):
                    continue
                ends[role].setdefault(end, {})[node] = list(types)
    return GraphSnapshot(names, ends)


def _endpoint_findings(kind_of_end: str, expected: str, type_name: str, role: str, graph: GraphSnapshot) -> list[Diagnosis]:
    """``other_type``, ``no_peer`` and ``near_name`` for one expected topic or service end."""
    ends = graph.ends[role]
    verb = _VERB[role]
    out = []
    here = ends.get(expected, {})
    if here:
        for node, types in here.items():
            if type_name not in types:
                shown = ", ".join(clean(t) for t in types)
                out.append(Diagnosis("other_type", f"node {clean(node)} {verb} {clean(expected)} as {shown}; "
                                     f"the lesson's type is {clean(type_name)}",
                                     {"name": expected, "node": node, "found_type": shown, "type": type_name}))
        return out
    out.append(Diagnosis("no_peer", f"no node {verb} the {kind_of_end} {clean(expected)}",
                         {"name": expected, "role": role}))
    near = near_names(expected, list(ends))
    if not near:  # the only end of the expected type, whatever its name (a rename the graders still follow)
        same_type = [end for end, nodes in ends.items() if any(type_name in ts for ts in nodes.values())]
        near = same_type if len(same_type) == 1 else []
    for end in near:
        for node, types in list(ends[end].items())[:1]:
            shown = ", ".join(short_type(t) for t in types)
            out.append(Diagnosis("near_name", f"node {clean(node)} {verb} {clean(end)} ({shown}), "
                                 f"{how_near(expected, end)}",
                                 {"expected": expected, "found": end, "node": node, "type": ", ".join(types)}))
    return out


def _qos_findings(ros_node: Any, topic: str) -> list[Diagnosis]:
    """``qos``: every publisher/subscription pair on ``topic`` involving a learner's node that cannot match."""
    from rclpy.qos import QoSCompatibility, qos_check_compatible  # noqa: PLC0415 - rclpy only when grading

    def who(info: Any) -> str:
        node = f"{info.node_namespace.rstrip('/')}/{info.node_name}"
        return "the grader" if info.node_name.startswith("_") else f"node {clean(node)}"

    out = []
    subscriptions = ros_node.get_subscriptions_info_by_topic(topic)
    for pub in ros_node.get_publishers_info_by_topic(topic):
        for sub in subscriptions:
            if pub.node_name.startswith("_") and sub.node_name.startswith("_"):
                continue  # the grader's own pair is not the learner's problem
            compatibility, reason = qos_check_compatible(pub.qos_profile, sub.qos_profile)
            if compatibility != QoSCompatibility.ERROR:
                continue
            pub_qos, sub_qos = describe_qos(pub.qos_profile), describe_qos(sub.qos_profile)
            out.append(Diagnosis(
                "qos", f"on {clean(topic)} the publisher of {who(pub)} ({pub_qos}) and the subscription of "
                f"{who(sub)} ({sub_qos}) cannot connect: "
                f"{clean(reason).strip().rstrip(';')[:160] or 'incompatible QoS'}",
                {"topic": topic, "publisher": who(pub), "publisher_qos": pub_qos, "subscription": who(sub),
                 "subscription_qos": sub_qos}))
    return out


#: setuptools' console-script wrapper names its distribution: ``__requires__ = 'pkg==0.0.0'`` (or the
#: ``EASY-INSTALL-ENTRY-SCRIPT: 'pkg==0.0.0','console_scripts','name'`` header of older setuptools).
_REQUIRES = re.compile(r"""(?:__requires__\s*=\s*|EASY-INSTALL-ENTRY-SCRIPT:\s*)['"]([A-Za-z0-9_.-]+)""")


def missing_entry_point(program: Path) -> Diagnosis | None:
    """``process``: the console script ``program`` (``install/<pkg>/lib/<pkg>/<name>``) loads an entry point
    that the installed metadata it finds first does not list.

    The script setuptools writes for ``ament_python`` packages calls
    ``importlib.metadata.distribution(<name>)`` and takes the ``console_scripts`` entry called
    ``<name>`` from it (``next(matches)``: a ``StopIteration`` when absent). The same lookup is done
    here with :mod:`importlib.metadata` on the package's ``lib/python3.*/site-packages``. None when
    ``program`` is no such script, or its entry point is there. Never raises.
    """
    try:
        with program.open("rb") as script:  # a wrapper's head, never a whole binary (an interpreter)
            head = script.read(4000).decode("utf-8", errors="replace")
        found = _REQUIRES.search(head)
        if found is None or program.parent.parent.name != "lib":
            return None
        dist_name = found.group(1).split("==")[0]
        prefix = program.parent.parent.parent
        sites = sorted(str(p) for p in prefix.glob("lib/python3*/site-packages") if p.is_dir())
        import importlib.metadata  # noqa: PLC0415 - only a failed start needs it (12 ms every check paid before its node ran)

        dist = next(iter(importlib.metadata.distributions(name=dist_name, path=sites)), None)
        if dist is None:
            return Diagnosis("process", f"{clean(program.name)} loads package {clean(dist_name)}, but no metadata "
                             f"of it is installed in {clean(str(prefix))} (rebuild it: colcon build)",
                             {"program": program.name, "distribution": dist_name})
        scripts = sorted(e.name for e in dist.entry_points if e.group == "console_scripts")
        if program.name in scripts:
            return None
        where = Path(str(dist._path)) if hasattr(dist, "_path") else Path(dist_name)  # noqa: SLF001 - its folder name
        listed = ", ".join(clean(n) for n in scripts[:6]) or "none"
        return Diagnosis("process", f"the entry point {clean(program.name)} is not in the installed metadata "
                         f"{clean(where.name)} (its console_scripts: {listed}): declare it in setup.py's "
                         "entry_points and rebuild",
                         {"program": program.name, "metadata": where.name, "console_scripts": listed})
    except Exception:  # noqa: BLE001 - advice only
        LOG.debug("entry point diagnosis of %s failed", program, exc_info=True)
        return None


def process_findings(processes: Iterable[LearnerProcess]) -> list[Diagnosis]:
    """``process``: each of ``processes`` that ended before the grader stopped it, and why if it can be told."""
    out = []
    for proc in processes:
        if not proc.exited_on_its_own():
            continue
        ended = proc.exit_state()
        if ended is None:
            continue
        last = f": {clean(ended.last_line)[:160]}" if ended.last_line else ""
        out.append(Diagnosis("process", f"the learner's process {clean(proc.name)} {ended.describe()}{last}",
                             {"process": proc.name, "returncode": str(ended.returncode),
                              "seconds": "" if ended.seconds is None else f"{ended.seconds:.2f}",
                              "signal": ended.signal_name or "", "last": ended.last_line}))
        if ended.returncode != 0 and (entry := missing_entry_point(proc.program)) is not None:
            out.append(entry)
    return out


def silent_topics(ros: Any) -> set[str]:
    """The topics on which a grader's probe has had a matched publisher (DDS's ``matched`` event: the same
    type, compatible QoS) for at least :data:`SILENT_AFTER` seconds, and nothing arrived since the match.

    Args:
        ros: the :class:`~ros2course.run.probes.RosSession`: its probes keep ``matched`` (since when)
            and ``heard`` (the last message, :func:`ros2course.run.probes.record`).
    """
    now = time.monotonic()
    return {topic for topic, first in dict(ros.matched).items()
            if now - first >= SILENT_AFTER and ros.heard.get(topic, float("-inf")) < first}


def _silent_findings(contract: LessonGraph, graph: GraphSnapshot, silent: set[str]) -> list[Diagnosis]:
    out = []
    for topic in contract.topics:
        if topic.role != "publish" or topic.name not in silent:
            continue
        nodes = [node for node, types in graph.ends["publish"].get(topic.name, {}).items() if topic.type in types]
        if nodes:
            out.append(Diagnosis("silent", f"node {clean(nodes[0])} has a publisher on {clean(topic.name)} "
                                 f"({short_type(topic.type)}) that the grader's subscription matched "
                                 f"{SILENT_AFTER:.0f}+ s ago, but nothing was published: does it spin "
                                 "(rclpy.spin) and is its timer created?",
                                 {"node": nodes[0], "topic": topic.name, "type": topic.type}))
    return out


def diagnose(graph: GraphSnapshot | None, contract: LessonGraph, *, ros_node: Any = None,
             processes: Sequence[LearnerProcess] = (), silent: set[str] | frozenset[str] = frozenset()
             ) -> list[Diagnosis]:
    """Compare what the part showed with the ``contract`` entries; return what explains a failure.

    Args:
        graph: the graph as observed (:func:`snapshot`), or None when it could not be read.
        contract: the entries that apply to the failed check's part (:meth:`LessonGraph.for_part`).
        ros_node: the grader's rclpy ``Node`` in that graph, for the QoS profiles of the expected
            topics that are there (queried only then); None: no ``qos`` findings.
        processes: the learner processes the part started (``process`` findings).
        silent: topics the engine established as matched yet silent (:func:`silent_topics`).

    Returns:
        at most :data:`MAX_FINDINGS` findings, the learner's processes first; ``[]`` when all
        matches the contract, or when any query failed (logged at debug level). Never raises.
    """
    out: list[Diagnosis] = []
    try:
        out += process_findings(processes)
    except Exception:  # noqa: BLE001 - a diagnosis is advice; it must never fail a check
        LOG.debug("process diagnosis failed", exc_info=True)
    try:
        if graph is not None:  # a process that died leaves its topics silent: that is not a second cause
            out += _diagnose(graph, contract, ros_node, frozenset() if out else silent)
    except Exception:  # noqa: BLE001 - a diagnosis is advice; it must never fail a check
        LOG.debug("graph diagnosis failed", exc_info=True)
    return out[:MAX_FINDINGS]


def _diagnose(graph: GraphSnapshot, contract: LessonGraph, ros_node: Any, silent: set[str] | frozenset[str]
              ) -> list[Diagnosis]:
    if not graph.names:
        return []
    out: list[Diagnosis] = []
    for name, count in sorted(collections.Counter(graph.names).items()):
        if count > 1:
            out.append(Diagnosis("duplicate_node", f"{count} nodes in the graph are named {clean(name)}: "
                                 "its parameters and services are ambiguous (give each node its own name)",
                                 {"name": name, "count": str(count)}))
    for node in contract.nodes:
        if node.name in graph.names:
            continue
        for found in near_names(node.name, graph.names):
            out.append(Diagnosis("near_name", f"no node {clean(node.name)}; node {clean(found)} is running, "
                                 f"{how_near(node.name, found)}", {"expected": node.name, "found": found}))
    for topic in contract.topics:
        out += _endpoint_findings("topic", topic.name, topic.type, topic.role, graph)
        if ros_node is not None and topic.name in graph.ends[topic.role]:
            try:
                out += _qos_findings(ros_node, topic.name)
            except Exception:  # noqa: BLE001 - QoS introspection failed: the other findings stay
                LOG.debug("QoS diagnosis of %s failed", topic.name, exc_info=True)
    for service in contract.services:
        out += _endpoint_findings("service", service.name, service.type, service.role, graph)
    if silent and not out:  # only a graph that otherwise matches the contract can be silent for certain
        out += _silent_findings(contract, graph, set(silent))
    return out
