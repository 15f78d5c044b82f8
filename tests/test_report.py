"""Rendering of results: the table of checks and the sparklines of observed time series."""

from __future__ import annotations

import io
import json
import math

import pytest
from rich.console import Console

from ros2course.grade.checklist import Check
from ros2course.grade.session import GradingSession
from ros2course.grade.results import CheckResult, LessonResult, Plot
from ros2course.report.table import render_result, result_json, sparkline


def _console() -> Console:
    return Console(file=io.StringIO(), width=110, color_system=None)


def test_sparkline_scales_lowest_to_highest_glyph():
    assert sparkline([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]) == "▁▂▃▄▅▆▇█"
    assert sparkline([5.0, 5.0, 5.0]) == "▄▄▄", "a flat series sits at mid height"
    assert sparkline([]) == ""


def test_sparkline_resamples_to_width_keeping_both_ends():
    values = [float(i) for i in range(1000)]
    line = sparkline(values, width=40)
    assert len(line) == 40
    assert line[0] == "▁" and line[-1] == "█"


def test_sparkline_fixed_scale_clamps():
    assert sparkline([-10.0, 0.0, 10.0], low=0.0, high=1.0) == "▁▁█"


def test_plots_render_under_the_table_but_stay_out_of_json():
    times = [i * 0.02 for i in range(100)]
    series = {f"joint {j}": [10 * math.sin(3 * t + j) for t in times] for j in range(1, 7)}
    check = CheckResult("rate", "It publishes at 500 Hz", 2, 2, True, "500.1 Hz", "500 Hz ± 5 %", "")
    result = LessonResult("sas-robot-driver", 2, 2, "passed", [check],
                          plots=[Plot("joints of /myrobot_1", times, series, "deg")])
    console = _console()
    render_result(result, console)
    text = console.file.getvalue()
    assert "joints of /myrobot_1 (1.98 s)" in text
    for j in range(1, 7):
        assert f"joint {j}" in text
    assert "-10 … 10 deg" in text
    assert "plots" not in json.loads(result_json(result)), "check --json keeps its documented shape"


def test_add_plot_rejects_series_of_the_wrong_length(tmp_path):
    session = GradingSession(None, [Check("a", "a", 1)], tmp_path, tmp_path / "log", {})  # no ROS: plots only
    session.add_plot("ok", [0.0, 1.0], {"a": [1, 2]}, "rad")
    assert session.plots[0].series == {"a": [1.0, 2.0]}
    with pytest.raises(ValueError, match="series 'b' has 1 values for 2 times"):
        session.add_plot("bad", [0.0, 1.0], {"b": [1]})
    session.close()
