"""``ros2course graph``: the contract's graph beside the one the last check observed (issue 19).

The observed side is written by the engine (tests/test_diagnose.py launches a real node and
reads its ``graph.json``); here the comparison, its Mermaid text and the command itself run
on a check's log folder as the engine leaves it.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from ros2course.lesson.catalog import LessonGraph, load_catalog
from ros2course.report.graph import compare, load_observed, mermaid
from ros2course.run.diagnose import GraphSnapshot


@pytest.fixture
def cli():
    """The CLI in this process (typer's CliRunner): no process boundary is under test here (issue 23)."""
    from conftest import run_cli_in_process

    return run_cli_in_process

QUOTE = "package_with_interfaces/msg/AmazingQuote"
CONTRACT = LessonGraph.validate({
    "nodes": [{"name": "/amazing_quote_publisher_node"}, {"name": "/amazing_quote_subscriber_node"}],
    "topics": [{"name": "/amazing_quote", "type": QUOTE},
               {"name": "/amazing_quote", "type": QUOTE, "role": "subscribe"}]})


def _observed() -> GraphSnapshot:
    """A publisher one character off, a subscriber on the right topic with another type, a stray node."""
    return GraphSnapshot(
        ["/amazing_quote_publisher_node", "/stray"],
        {"publish": {"/amazing_quotes": {"/amazing_quote_publisher_node": [QUOTE]}},
         "subscribe": {"/amazing_quote": {"/stray": ["std_msgs/msg/String"]}}, "serve": {}, "call": {}})


def test_each_entry_is_matched_missing_of_another_type_or_unexpected() -> None:
    rows = compare(CONTRACT, _observed())
    got = [(r.kind, r.name, r.role, r.status) for r in rows]
    assert got == [
        ("node", "/amazing_quote_publisher_node", "", "matched"),
        ("node", "/amazing_quote_subscriber_node", "", "missing"),
        ("topic", "/amazing_quote", "publish", "missing"),
        ("topic", "/amazing_quote", "subscribe", "other type"),
        ("node", "/stray", "", "unexpected"),
        ("topic", "/amazing_quotes", "publish", "unexpected"),
    ]
    other = rows[3]
    assert other.nodes == ["/stray (std_msgs/msg/String)"] and other.type == QUOTE


def test_without_a_contract_everything_is_observed() -> None:
    rows = compare(None, _observed())
    assert {r.status for r in rows} == {"observed"}
    assert ("topic", "/amazing_quotes") in {(r.kind, r.name) for r in rows}


def test_mermaid_draws_edges_and_marks_what_is_missing() -> None:
    text = mermaid(compare(CONTRACT, _observed()))
    assert text.startswith("flowchart LR\n")
    lines = text.splitlines()
    ids = {line.split("[", 1)[0].split("(", 1)[0].split("{", 1)[0].strip(): line for line in lines[1:]
           if '"' in line}
    publisher = next(i for i, line in ids.items() if "/amazing_quote_publisher_node" in line)
    wrong_topic = next(i for i, line in ids.items() if "/amazing_quotes" in line)
    assert f"  {publisher} --> {wrong_topic}" in lines  # a publisher points at its topic
    missing = next(line for line in lines if line.startswith("  class ") and line.endswith(" missing"))
    subscriber = next(i for i, line in ids.items() if "/amazing_quote_subscriber_node" in line)
    assert subscriber in missing.split()[1].split(",")


def test_mermaid_labels_are_escaped() -> None:
    odd = GraphSnapshot(['/a"b<c>'], {"publish": {}, "subscribe": {}, "serve": {}, "call": {}})
    text = mermaid(compare(None, odd))
    assert '"/a#quot;b#lt;c#gt;"' in text


def _workspace_with_a_check(tmp_path: Path, cli) -> Path:
    ws = tmp_path / "ws"
    assert cli("init", str(ws)).returncode == 0
    latest = ws / "log" / "ros2course" / "publisher-subscriber" / "latest"
    latest.mkdir(parents=True)
    (latest / "observed.mcap").write_bytes(b"")
    parts = [{"part": "publisher", **_observed().to_dict()}]
    (latest / "graph.json").write_text(json.dumps({"lesson": "publisher-subscriber", "parts": parts}))
    return ws


def test_the_command_prints_both_sides_and_writes_mermaid(tmp_path, cli) -> None:
    assert load_catalog().get("publisher-subscriber").graph is not None
    ws = _workspace_with_a_check(tmp_path, cli)
    proc = cli("graph", "publisher-subscriber", "--mermaid", str(tmp_path / "g.mmd"), "-w", str(ws))
    assert proc.returncode == 0, proc.stderr
    assert "missing" in proc.stdout and "unexpected" in proc.stdout and "/amazing_quotes" in proc.stdout
    assert (tmp_path / "g.mmd").read_text().startswith("flowchart LR")
    assert load_observed(ws / "log" / "ros2course" / "publisher-subscriber" / "latest").names[0] \
        == "/amazing_quote_publisher_node"


def test_no_check_yet_is_one_line_and_a_non_zero_exit(tmp_path, cli) -> None:
    ws = tmp_path / "ws"
    assert cli("init", str(ws)).returncode == 0
    proc = cli("graph", "publisher-subscriber", "-w", str(ws))
    assert proc.returncode != 0
    assert "no check of publisher-subscriber has run" in proc.stderr and "Traceback" not in proc.stderr
    latest = ws / "log" / "ros2course" / "publisher-subscriber" / "latest"
    latest.mkdir(parents=True)
    (latest / "observed.mcap").write_bytes(b"")
    proc = cli("graph", "publisher-subscriber", "-w", str(ws))
    assert proc.returncode != 0 and "no recorded graph" in proc.stderr


def test_feedback_leads_with_the_failure_whose_cause_is_known() -> None:
    """``fix first:`` names the earliest failed check with a diagnosis, else the earliest judged failure."""
    import io  # noqa: PLC0415

    from rich.console import Console  # noqa: PLC0415

    from ros2course.grade.results import CheckResult, LessonResult  # noqa: PLC0415
    from ros2course.report.table import render_result  # noqa: PLC0415
    from ros2course.run.diagnose import Diagnosis  # noqa: PLC0415

    def check(check_id: str, passed: bool, diagnosis=(), skipped=False) -> CheckResult:
        return CheckResult(check_id, f"check {check_id}", 1.0 if passed else 0.0, 1.0, passed, "seen", "wanted",
                           "" if passed else f"hint {check_id}", skipped=skipped, diagnosis=list(diagnosis))

    why = Diagnosis("near_name", "node /talker publishes /chatter2, one character from /chatter", {})
    result = LessonResult("l", 1.0, 4.0, "failed", [check("a", True), check("b", False), check("c", False, [why]),
                                                    check("d", False, skipped=True)])
    assert result.first_fix().id == "c"
    assert LessonResult("l", 1.0, 3.0, "failed", [check("a", True), check("b", False), check("c", False)]
                        ).first_fix().id == "b"
    assert LessonResult("l", 1.0, 2.0, "failed", [check("a", True), check("b", False)]).first_fix() is None
    out = io.StringIO()
    render_result(result, Console(file=out, width=200, color_system=None))
    text = out.getvalue()
    assert "fix first: check c (node /talker publishes /chatter2, one character from /chatter)" in text
    assert text.index("fix first:") < text.index("✘ check b")


def test_evidence_plots_draw_the_band_and_refuse_a_bad_file(tmp_path) -> None:
    """``evidence --plot`` (uniplot) and ``--png`` (matplotlib) on a series; a folder as --png is one clear error."""
    import io  # noqa: PLC0415

    import pytest  # noqa: PLC0415
    from rich.console import Console  # noqa: PLC0415

    from ros2course.errors import CourseError  # noqa: PLC0415
    from ros2course.report.evidence import IntervalSeries, plot_png, plot_terminal  # noqa: PLC0415

    series = [IntervalSeries("rate: /rosout from talker", [0.5, 1.0, 1.3, 1.8], [0.5, 0.5, 0.3, 0.5], (0.425, 0.575))]
    out = io.StringIO()
    plot_terminal(series, Console(file=out, width=100, color_system=None))
    assert "their mean must lie in 0.425-0.575 s" in out.getvalue() and "┌" in out.getvalue()
    plot_png(series, tmp_path / "r.png")
    assert (tmp_path / "r.png").read_bytes()[:4] == b"\x89PNG"
    # a stream judged on its median (kit.rate(median=True), sas's 500 Hz joint states) says so
    median = [IntervalSeries("stream_rate: /joint_states", [0.002, 0.004, 0.016], [0.002, 0.002, 0.012],
                             (0.0017, 0.0023), "median")]
    out = io.StringIO()
    plot_terminal(median, Console(file=out, width=100, color_system=None))
    assert "their median must lie in 1.70-2.30 ms" in out.getvalue()
    plot_png(median, tmp_path / "m.png")
    with pytest.raises(CourseError, match="cannot write"):
        plot_png(series, tmp_path)
    with pytest.raises(CourseError, match="nothing to plot"):
        plot_png([], tmp_path / "empty.png")
