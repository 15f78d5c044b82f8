"""``ros2course graph``: the graph a lesson's contract expects beside the one its last check observed (issue 19).

The expected side is the lesson's ``graph:`` declaration
(:class:`ros2course.lesson.catalog.LessonGraph`); the observed side is the
check's ``graph.json`` (:data:`ros2course.grade.observer.GRAPH_FILE`): what the
graph showed in each grader part, at its first verdict after the learner's
nodes were launched (:class:`ros2course.run.diagnose.GraphSnapshot`). Each
entry is marked ``matched``, ``missing`` (expected, not seen), ``other type``
(the name is there with another type) or ``unexpected`` (seen, not in the
contract; listed only when the lesson declares a graph).

``--mermaid FILE`` writes the same as a Mermaid flowchart (our own emitter:
the ros2_graph project that draws ROS graphs as Mermaid is GPL-3.0). Nodes are
boxes, topics stadiums, services hexagons; a publisher points at its topic, a
topic at its subscriber, a client at its service, a service at its server.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from ros2course.errors import CourseError
from ros2course.grade.observer import GRAPH_FILE
from ros2course.run.diagnose import GraphSnapshot, clean

#: How each role reads in a table (topics and services).
ROLE_WORDS = {"publish": "published by", "subscribe": "subscribed by", "serve": "served by", "call": "called by"}
#: Row marks, for people (rich markup) and for Mermaid class names.
MARKS = {"matched": "[green]✔ matched[/]", "missing": "[red]✘ missing[/]", "other type": "[red]✘ other type[/]",
         "unexpected": "[yellow]+ unexpected[/]", "observed": "[cyan]• observed[/]"}


@dataclasses.dataclass
class GraphRow:
    """One entry of the comparison.

    Attributes:
        kind: ``node``, ``topic`` or ``service``.
        name: fully qualified name.
        role: for topics and services, ``publish``/``subscribe``/``serve``/``call``; "" for nodes.
        type: the expected type (or the observed one for an unexpected entry); "" for nodes.
        status: ``matched``, ``missing``, ``other type``, ``unexpected``, or ``observed`` (no contract).
        nodes: the learner nodes seen holding this endpoint, each with its types (``/n (pkg/msg/T)``).
    """

    kind: str
    name: str
    role: str
    type: str
    status: str
    nodes: list[str] = dataclasses.field(default_factory=list)


def load_observed(log_dir: Path) -> GraphSnapshot:
    """The union of every part's snapshot in ``log_dir``'s ``graph.json``.

    Raises:
        CourseError: no graph file there (the check watched no learner node, or never ran).
    """
    path = log_dir / GRAPH_FILE
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise CourseError(f"no recorded graph in {log_dir}: that check started no ROS node of yours",
                          "run `ros2course check` on a lesson whose nodes the grader launches") from None
    except (OSError, ValueError) as exc:
        raise CourseError(f"{path} is unreadable ({exc})", "run the check again") from exc
    merged = GraphSnapshot([], {role: {} for role in ROLE_WORDS})
    for part in data.get("parts", []):
        one = GraphSnapshot.from_dict(part)
        merged.names += [n for n in one.names if n not in merged.names]
        for role, by_name in one.ends.items():
            for name, by_node in by_name.items():
                merged.ends[role].setdefault(name, {}).update(by_node)
    return merged


def compare(expected: Any, observed: GraphSnapshot) -> list[GraphRow]:
    """Rows of expected vs observed entries, contract order first, then the unexpected (sorted).

    Args:
        expected: the lesson's :class:`~ros2course.lesson.catalog.LessonGraph`, or None (every
            observed entry is then listed as ``observed``).
        observed: the merged snapshot (:func:`load_observed`).
    """
    rows: list[GraphRow] = []
    declared = expected is not None
    known_nodes: set[str] = set()
    known_ends: set[tuple[str, str]] = set()
    for node in (expected.nodes if declared else []):
        known_nodes.add(node.name)
        rows.append(GraphRow("node", node.name, "", "", "matched" if node.name in observed.names else "missing"))
    entries = [("topic", e) for e in (expected.topics if declared else [])]
    entries += [("service", e) for e in (expected.services if declared else [])]
    for kind, entry in entries:
        known_ends.add((entry.role, entry.name))
        by_node = observed.ends.get(entry.role, {}).get(entry.name, {})
        holders = [f"{node} ({', '.join(types)})" for node, types in sorted(by_node.items())]
        if any(entry.type in types for types in by_node.values()):
            status = "matched"
        elif by_node:
            status = "other type"
        else:
            status = "missing"
        rows.append(GraphRow(kind, entry.name, entry.role, entry.type, status, holders))
    extra = "unexpected" if declared else "observed"
    for name in sorted(set(observed.names) - known_nodes):
        rows.append(GraphRow("node", name, "", "", extra))
    for role in ROLE_WORDS:
        for name, by_node in sorted(observed.ends.get(role, {}).items()):
            if (role, name) in known_ends:
                continue
            types = sorted({t for ts in by_node.values() for t in ts})
            rows.append(GraphRow("topic" if role in ("publish", "subscribe") else "service", name, role,
                                 ", ".join(types), extra,
                                 [f"{node} ({', '.join(ts)})" for node, ts in sorted(by_node.items())]))
    return rows


def render(rows: list[GraphRow], lesson_id: str, console: Console) -> None:
    """The comparison as a table, then a one-line count."""
    table = Table(title=f"ros2course graph {lesson_id}: expected beside observed", title_justify="left")
    for column in ("", "kind", "name", "type", "seen"):
        table.add_column(column, overflow="fold")
    for row in rows:
        seen = "; ".join(f"{ROLE_WORDS.get(row.role, 'by')} {clean(holder)}" for holder in row.nodes[:4])
        if len(row.nodes) > 4:
            seen += f"; and {len(row.nodes) - 4} more"
        table.add_row(MARKS[row.status], row.kind, clean(row.name), row.type, seen or ("running" if row.kind == "node"
                                                                                         and row.status != "missing"
                                                                                         else ""))
    console.print(table)
    counts = {status: sum(r.status == status for r in rows) for status in MARKS}
    console.print(", ".join(f"{n} {status}" for status, n in counts.items() if n) or "the graph is empty")


def _label(text: str) -> str:
    """A Mermaid label: quotes and angle brackets as entities (Mermaid's own ``#quot;`` escapes)."""
    return clean(text).replace('"', "#quot;").replace("<", "#lt;").replace(">", "#gt;")


def mermaid(rows: list[GraphRow]) -> str:
    """The comparison as a Mermaid ``flowchart LR`` (text), missing entries dashed red, unexpected orange."""
    lines = ["flowchart LR"]
    ids: dict[tuple[str, str], str] = {}

    def ident(kind: str, name: str) -> str:
        key = (kind, name)
        if key not in ids:
            ids[key] = f"{kind[0]}{len(ids)}"
        return ids[key]

    shapes = {"node": ('["', '"]'), "topic": ('(["', '"])'), "service": ('{{"', '"}}')}
    classes: dict[str, list[str]] = {"missing": [], "unexpected": [], "othertype": []}
    drawn: set[str] = set()
    for row in rows:
        node_id = ident(row.kind, row.name)
        if node_id not in drawn:
            left, right = shapes[row.kind]
            text = row.name + (f"<br/>{row.type}" if row.type else "")
            lines.append(f"  {node_id}{left}{_label(text).replace('#lt;br/#gt;', '<br/>')}{right}")
            drawn.add(node_id)
        status = row.status.replace(" ", "")
        if status in classes and node_id not in classes[status]:
            classes[status].append(node_id)
        for holder in row.nodes:
            node_name = holder.split(" (", 1)[0]
            holder_id = ident("node", node_name)
            if holder_id not in drawn:
                lines.append(f'  {holder_id}["{_label(node_name)}"]')
                drawn.add(holder_id)
            if row.role in ("publish", "call"):
                lines.append(f"  {holder_id} --> {node_id}")
            else:
                lines.append(f"  {node_id} --> {holder_id}")
    lines += ["  classDef missing stroke:#c00,stroke-width:2px,stroke-dasharray:5 3",
              "  classDef othertype stroke:#c00,stroke-width:2px",
              "  classDef unexpected stroke:#d80,stroke-width:2px"]
    lines += [f"  class {','.join(members)} {name}" for name, members in classes.items() if members]
    return "\n".join(lines) + "\n"


__all__ = ["GRAPH_FILE", "GraphRow", "compare", "load_observed", "mermaid", "render"]
