"""Rendering results for people (rich) and programs (JSON).

Every renderer takes an injected rich ``Console`` (rich's own testing idiom:
``Console(file=io.StringIO(), width=100)``), so tests compare plain text.
"""

from __future__ import annotations

import json

from rich.console import Console, Group
from rich.panel import Panel
from rich.table import Table
from rich.text import Text

from ros2course.grade.results import LessonResult, Plot, Status
from ros2course.lesson.catalog import Lesson
from ros2course.report.listing import points_text

_STATUS_STYLE = {Status.PASSED: "bold green", Status.FAILED: "bold yellow", Status.NOT_GRADABLE: "bold red",
                 Status.GRADER_ERROR: "bold magenta"}


#: Eight block glyphs, lowest to highest. rich has no sparkline renderable and a plotting
#: dependency (plotext, asciichartpy) would be heavier than this one mapping.
_SPARK = "▁▂▃▄▅▆▇█"


def sparkline(values: list[float], width: int = 60, low: float | None = None, high: float | None = None) -> str:
    """``values`` as a string of at most ``width`` block glyphs (evenly resampled).

    ``low``/``high`` fix the scale (default: the values' own range); a flat
    series is drawn at mid height.
    """
    if not values:
        return ""
    if len(values) > width:
        values = [values[round(i * (len(values) - 1) / (width - 1))] for i in range(width)]
    low = min(values) if low is None else low
    high = max(values) if high is None else high
    if high - low < 1e-12:
        return _SPARK[3] * len(values)
    top = len(_SPARK) - 1
    return "".join(_SPARK[max(0, min(top, round((v - low) / (high - low) * top)))] for v in values)


def render_plot(plot: Plot, console: Console, width: int = 60) -> None:
    """One sparkline per series of ``plot``, each labelled with its range (in ``plot.unit``)."""
    if not plot.times or not plot.series:
        return
    span = plot.times[-1] - plot.times[0]
    table = Table(title=f"{plot.title} ({span:.2f} s)", title_justify="left", box=None, show_header=False,
                  padding=(0, 1))
    table.add_column(style="bold")
    table.add_column(style="cyan", no_wrap=True)
    table.add_column(style="dim", no_wrap=True)
    unit = f" {plot.unit}" if plot.unit else ""
    for label, values in plot.series.items():
        if not values:
            continue
        table.add_row(label, sparkline(values, width), f"{min(values):.3g} … {max(values):.3g}{unit}")
    console.print(table)


def render_result(result: LessonResult, console: Console) -> None:
    """Print the table of checks; under it, for each failed check, observed / expected / hint / why (its diagnosis)."""
    style = _STATUS_STYLE.get(result.status, "bold")
    title = Text.assemble((f"{result.lesson}: ", "bold"), (result.status.value, style),
                          f"  {points_text(result.score)}/{points_text(result.max_score)} points")
    if result.checks:
        table = Table(title=title, title_justify="left", show_lines=False, expand=False)
        table.add_column("", width=2)
        table.add_column("check")
        table.add_column("points", justify="right")
        table.add_column("observed", overflow="fold")
        for check in result.checks:
            mark = Text("✔", "green") if check.passed else Text("✘", "red")
            table.add_row(mark, check.name, f"{points_text(check.points)}/{points_text(check.max_points)}",
                          Text(check.observed, style="" if check.passed else "yellow"))
        console.print(table)
    else:
        console.print(title)
    if result.message:
        console.print(Panel(Text(result.message), title=result.status.value, border_style=style, expand=False))
    if result.hint:
        console.print(Text.assemble(("hint: ", "bold cyan"), result.hint))
    skipped = [c for c in result.checks if c.skipped]
    first = result.first_fix()
    if first is not None:
        reason = first.diagnosis[0].message if first.diagnosis else (first.hint or first.observed)
        console.print(Text.assemble(("fix first: ", "bold magenta"), (first.name, "bold"), f" ({reason})"))
    for check in result.checks:
        if check.passed or check.skipped:
            continue
        console.print(Text.assemble(("✘ ", "red"), (check.name, "bold")))
        console.print(Text.assemble(("    observed: ", "dim"), check.observed))
        console.print(Text.assemble(("    expected: ", "dim"), check.expected))
        if check.hint:
            console.print(Text.assemble(("    hint:     ", "cyan"), check.hint))
        for finding in check.diagnosis:  # what the graph showed (ros2course.run.diagnose)
            console.print(Text.assemble(("    why:      ", "magenta"), finding.message))
        if check.evidence:
            seconds = (check.evidence["end_ns"] - check.evidence["start_ns"]) * 1e-9
            console.print(Text.assemble(("    evidence: ", "dim"), f"ros2course evidence {result.lesson} {check.id}",
                                        (f"  ({seconds:.1f} s judged, recorded in {check.evidence['recording']})",
                                         "dim")))
    if skipped:
        console.print(Text(f"{len(skipped)} check(s) not run: {skipped[0].observed.removeprefix('not checked: ')}",
                           style="dim"))
    for plot in result.plots:
        render_plot(plot, console)
    if result.withheld:  # checks graded only when the work is handed in (issue 39): say so, never what they are
        more = f"{result.withheld} more check(s) are graded when you hand in your work"
        console.print(Text(f"All {len(result.checks)} visible checks passed; {more}." if result.status is Status.PASSED
                           else f"{more}; they are not shown here.", style="cyan"))
    if result.status is Status.PASSED:
        console.print(Text("Full marks. 'ros2course next' moves on.", style="green"))
    if result.log_dir:
        console.print(Text(f"logs: {result.log_dir}", style="dim"))


def result_json(result: LessonResult) -> str:
    """The ``check --json`` document (one JSON object, newline-terminated)."""
    return json.dumps(result.to_json(), indent=2) + "\n"


def render_lesson(lesson: Lesson, console: Console) -> None:
    """The lesson's title, chapters and instructions (markdown)."""
    source = (f"seed chapter(s): {', '.join(str(c) for c in lesson.chapters)}" if lesson.chapters
              else f"beyond the seed tutorial: {lesson.beyond}")
    console.print(Panel(Group(Text(lesson.title, style="bold"),
                              Text(f"lesson id: {lesson.id}   {source}", style="dim")),
                        expand=False))
    # rich.markdown pulls in markdown_it (~50 ms): only the commands that show instructions pay for it
    from rich.markdown import Markdown  # noqa: PLC0415 - start time of list

    console.print(Markdown(lesson.instructions))


def render_regrades(items: list, console: Console) -> None:
    """``check --all``'s summary: each passed lesson's new grade, regressions first in red.

    Args:
        items: :class:`ros2course.grade.regrade.Regrade` objects, in course order.
    """
    table = Table(title="ros2course check --all", title_justify="left")
    table.add_column("lesson")
    table.add_column("before", justify="right")
    table.add_column("now", justify="right")
    table.add_column("verdict")
    table.add_column("first failed check", overflow="fold")
    for item in items:
        result = item.result
        failed = next((c for c in result.checks if not c.passed and not c.skipped), None)
        first = (f"{failed.name}: {failed.observed}" if failed is not None
                 else (result.message.splitlines()[0] if result.message else ""))
        table.add_row(item.lesson.id, "-" if item.before is None else points_text(item.before),
                      f"{points_text(result.score)}/{points_text(result.max_score)}",
                      Text("REGRESSION", "bold red") if item.regression else Text("still passes", "green"),
                      first if item.regression else "")
    console.print(table)
    broken = [item.lesson.id for item in items if item.regression]
    if broken:
        console.print(Text(f"{len(broken)} of {len(items)} passed lessons fail now: {', '.join(broken)}. "
                           f"'ros2course check {broken[0]}' shows the details.", style="red"))
    else:
        console.print(Text(f"All {len(items)} passed lessons still pass.", style="green"))
