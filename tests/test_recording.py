"""Every check that watches the ROS graph leaves a recording (MCAP), and ``evidence`` reads it back.

The print-forever lesson is the example: its rate check judges /rosout
records' stamps, so the recording must hold those records and ``evidence``
must recompute the same rate from them; a node logging at the wrong rate
loses the check and its JSON names the recording and the window judged.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from ros2course.run.recording import CHECKS_METADATA, FILE_NAME

pytestmark = pytest.mark.ros

NODE = "src/python_package_with_a_node/python_package_with_a_node/print_forever_node.py"


def _check(cli, root: Path) -> dict:
    proc = cli("check", "print-forever-node", "--json", cwd=root)
    assert proc.returncode in (0, 1), proc.stderr
    return json.loads(proc.stdout)


def test_recording_holds_what_the_rate_check_judged(solution_workspace, cli):
    root = solution_workspace.root
    result = _check(cli, root)
    assert result["status"] == "passed", result
    rate = next(c for c in result["checks"] if c["id"] == "rate")
    assert "evidence" not in rate  # passed checks keep the documented JSON shape

    recording = root / "log" / "ros2course" / "print-forever-node" / "latest" / FILE_NAME
    with recording.open("rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        records = [msg for _, channel, _, msg in reader.iter_decoded_messages() if channel.topic == "/rosout"]
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    texts = [r.msg for r in records if r.name == "print_forever"]
    assert texts[:6] == [f"Printed {n} times." for n in range(6)]
    assert set(metadata[CHECKS_METADATA]) >= {"rate", "log_format", "node_name"}

    shown = cli("evidence", "print-forever-node", "rate", cwd=root)
    assert shown.returncode == 0, shown.stderr
    described = rate["observed"].split(" (from ")[0]  # "2.00 Hz (mean period 0.500 s, ..., 5 intervals)"
    assert f"/rosout from print_forever: {described}" in " ".join(shown.stdout.split())


def test_a_failed_check_names_its_recording(solution_workspace, cli):
    root = solution_workspace.root
    node = root / NODE
    node.write_text(node.read_text(encoding="utf-8").replace("timer_period: float = 0.5", "timer_period: float = 0.3"),
                    encoding="utf-8")
    result = _check(cli, root)
    rate = next(c for c in result["checks"] if c["id"] == "rate")
    assert not rate["passed"], rate
    evidence = rate["evidence"]
    assert Path(evidence["recording"]).is_file() and evidence["start_ns"] < evidence["end_ns"]
    shown = cli("evidence", "print-forever-node", cwd=root)  # default: the failed checks
    assert shown.returncode == 0, shown.stderr
    assert "rate: failed" in shown.stdout and rate["observed"].split(" (from ")[0] in " ".join(shown.stdout.split())
    # the same window drawn (issue 19): the intervals over time, the band the mean had to lie in
    png = root / "rate.png"
    plotted = cli("evidence", "print-forever-node", "rate", "--plot", "--png", str(png), cwd=root)
    assert plotted.returncode == 0, plotted.stderr
    assert "their mean must lie in 0.425-0.575 s" in plotted.stdout and "┌" in plotted.stdout
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # and the graph it ran in, beside the lesson's contract
    graph = cli("graph", "print-forever-node", cwd=root)
    assert graph.returncode == 0, graph.stderr
    assert "✔ matched" in graph.stdout and "/print_forever" in graph.stdout


def test_evidence_without_a_check_run(workspace, cli):
    proc = cli("evidence", "print-forever-node", cwd=workspace.root)
    assert proc.returncode == 5 and "run 'ros2course check print-forever-node' first" in proc.stderr
