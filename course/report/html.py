"""``ros2course report OUTDIR``: the instructor's view of a batch-graded class (issue 21).

The report is rebuilt only from ``OUTDIR/results.jsonl``, the per-student folders (logs and
``observed.mcap`` recordings) and, for similarity, the submissions folder, so it can be
regenerated at any time (after ``--resume`` too). It is one self-contained HTML file: inline
styles, inline SVG charts drawn by matplotlib, no script and no external URL.

Every piece of text goes through a Jinja2 template with autoescaping on, so student-controlled
text (ids, node output, file contents, messages) is always escaped; only the SVG that matplotlib
renders from numbers is inserted as markup.
"""

from __future__ import annotations

import collections
import dataclasses
import io
import itertools
import math
import os
import re
import statistics
import urllib.parse
from pathlib import Path
from typing import Any

from ros2course.errors import CourseError
from ros2course.files import atomic_write_text
from ros2course.grade.results import LessonResult, Status
from ros2course.report.gradebook import latest, read_regrades, read_results_counted

#: Plots of recorded rates drawn in one report (each costs ~50 ms); the rest say where to look.
MAX_PLOTS = 40
#: Recordings larger than this (bytes) are not read for plots: decoding costs ~50 µs a message and a
#: compressed MB holds ~40,000 (a sas check's 5,000 joint states at 500 Hz: 0.13 MB, read in 0.25 s).
MAX_RECORDING_BYTES = 2_000_000
#: Streams drawn per plot, and intervals drawn per stream.
MAX_STREAMS, MAX_POINTS = 3, 400
#: Similar pairs listed.
MAX_PAIRS = 50
#: The rate band of a check's expected text ("mean period 0.500 s ± 15%" or "median period ...": kit/judge.py;
#: "median period 2.0 ms ± 15%": graders/_sas.py, kit.rate(median=True)).
RATE_BAND = re.compile(r"(mean|median) period ([0-9.]+) (s|ms) ± ([0-9.]+)\s*%")

_STYLE = """
body{font-family:sans-serif;margin:2em;max-width:1150px;color:#222}
table{border-collapse:collapse;margin:0.5em 0}
td,th{border:1px solid #ccc;padding:3px 6px;vertical-align:top;font-size:90%;text-align:left}
th{background:#eee}
tr.pass td:first-child{border-left:4px solid #2a2}tr.fail td:first-child{border-left:4px solid #c22}
.pass{color:#060}.fail{color:#a00}.note{color:#666}
pre{white-space:pre-wrap;margin:0;max-height:18em;overflow:auto}
section.student{border-top:1px solid #ddd;margin-top:1em}
.plots{display:flex;flex-wrap:wrap;gap:1em}.plots figure{margin:0;max-width:540px;font-size:85%}
nav a{margin-right:1em}
"""

_TEMPLATE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta http-equiv="Content-Security-Policy" content="default-src 'none'; style-src 'unsafe-inline'; img-src data:">
<title>Class report: {{ title }}</title><style>{{ style }}</style></head>
<body><h1>Class report: {{ title }}</h1>
<nav><a href="#class">the class</a><a href="#checks">the checks</a><a href="#students">each student</a><a href="#similar">similar submissions</a></nav>
<p class="note">Built from {{ records }} result(s) in results.jsonl{% if skipped_lines %}; {{ skipped_lines }} line(s) could not be read (a truncated last line or a row from another version) and are left out{% endif %}.</p>

<h2 id="class">The class</h2>
{{ histogram }}
<table><tr><th>lesson</th><th>students</th><th>passed</th><th>pass rate</th><th>mean score</th></tr>
{% for lesson, row in lessons.items() %}<tr><td>{{ lesson }}</td><td>{{ row.students }}</td><td>{{ row.passed }}</td><td>{{ "%.0f" % (100 * row.rate) }}%</td><td>{{ "%.0f" % (100 * row.mean) }}%</td></tr>
{% endfor %}</table>
<p>Statuses: {% for status, count in statuses %}{{ status }}: {{ count }}{% if not loop.last %}, {% endif %}{% endfor %}.</p>
<p>Grading time: {% if median is not none %}median {{ "%.1f" % median }} s, slowest {{ "%.1f" % slowest }} s ({{ slowest_who }}){% else %}unknown (no timings in the records){% endif %}.</p>
<p>Isolation in effect:</p><ul>{% for text, count in isolation %}<li>{{ text }} ({{ count }} result(s))</li>{% endfor %}</ul>
<h3>Not gradable and grader errors</h3>
{% if unfinished %}<table><tr><th>student</th><th>lesson</th><th>status</th><th>reason</th><th>hint</th></tr>
{% for r in unfinished %}<tr><td><a href="#{{ r.anchor }}">{{ r.student }}</a></td><td>{{ r.lesson }}</td><td>{{ r.status }}</td><td><pre>{{ r.message }}</pre></td><td>{{ r.hint }}</td></tr>
{% endfor %}</table>{% else %}<p>none</p>{% endif %}

{% if adjustments %}<h2 id="deadlines">Deadlines and late policy</h2>
<p class="note">{{ adjustments.note }}</p>
{% if adjustments.rows %}<table><tr><th>student</th><th>lesson</th><th>raw score</th><th>adjusted score</th><th>reason</th></tr>
{% for a in adjustments.rows %}<tr><td>{{ a.student }}</td><td>{{ a.lesson }}</td><td>{{ a.raw }} / {{ a.max }}</td><td>{{ a.score }}</td><td>{{ a.reason }}</td></tr>
{% endfor %}</table>{% endif %}
{% endif %}
{% if regrades %}<h2 id="regrades">Regrades</h2>
<p class="note">{{ regrades.note }}</p>
<table><tr><th>student</th><th>lesson</th><th>score</th><th>checks whose points moved</th><th>why</th><th>graded with</th></tr>
{% for r in regrades.rows %}<tr><td>{{ r.student }}</td><td>{{ r.lesson }}</td><td>{{ r.score }}</td><td>{{ r.checks }}</td><td>{{ r.why }}</td><td>{{ r.graders }}</td></tr>
{% endfor %}</table>{% endif %}
<h2 id="checks">The checks</h2>
{% if checks %}<p>Sorted by how many lost each: what to re-teach first.</p>
<table><tr><th>lesson</th><th>check</th><th>lost by</th><th>most common observed (among those who lost it)</th></tr>
{% for row in checks %}<tr><td>{{ row.lesson }}</td><td>{{ row.name }}</td><td>{{ row.lost }} of {{ row.graded }}</td><td><pre>{{ row.observed }}</pre><span class="note">({{ row.observed_count }} of them)</span></td></tr>
{% endfor %}</table>{% else %}<p>no check was lost</p>{% endif %}

<h2 id="students">Each student</h2>
{% for s in students %}<section class="student" id="{{ s.anchor }}"><h3>{{ s.student }}: {{ s.lesson }}</h3>
<p><span class="{{ 'pass' if s.passed else 'fail' }}">{{ s.status }}</span>, {{ s.score }} / {{ s.max_score }}{% if s.seconds is not none %}, graded in {{ "%.1f" % s.seconds }} s{% endif %};
{% if s.logs %}<a href="{{ s.logs }}">logs</a>{% else %}logs: none{% endif %};
{% if s.recording %}<a href="{{ s.recording }}">recording</a> (<code>ros2course evidence</code>, Foxglove){% else %}no recording{% endif %}</p>
{% if s.message %}<pre>{{ s.message }}</pre>{% endif %}{% if s.hint %}<p>hint: {{ s.hint }}</p>{% endif %}
{% if s.checks %}<table><tr><th>check</th><th>points</th><th>observed</th><th>expected</th><th>hint</th></tr>
{% for c in s.checks %}<tr class="{{ 'pass' if c.passed else 'fail' }}"><td>{{ c.name }}</td><td>{{ "%g" % c.points }}/{{ "%g" % c.max_points }}</td><td><pre>{{ c.observed }}</pre></td><td><pre>{{ c.expected }}</pre></td><td>{{ c.hint if not c.passed else "" }}{% if not c.passed %}{% for d in c.diagnosis %}<br>why: {{ d.message }}{% endfor %}{% endif %}</td></tr>
{% endfor %}</table>{% else %}<p>no checks recorded</p>{% endif %}
{% if s.plots %}<div class="plots">{% for p in s.plots %}<figure>{{ p.svg }}<figcaption>{{ p.caption }}</figcaption></figure>{% endfor %}</div>{% endif %}
{% for note in s.plot_notes %}<p class="note">{{ note }}</p>{% endfor %}
</section>
{% endfor %}

<h2 id="similar">Similar submissions</h2>
<p class="note">{{ similarity.note }}</p>
{% for pair in similarity.pairs %}<h3>{{ pair.lesson }}: {{ pair.first }} / {{ pair.second }} ({{ "%.0f" % (100 * pair.score) }}%, {{ pair.shared_tokens }} tokens shared beyond boilerplate)</h3>
<table><tr><th>{{ pair.first }}: {{ pair.files[0] }}</th><th>{{ pair.second }}: {{ pair.files[1] }}</th></tr>
{% for left, right in pair.fragments %}<tr><td><pre>{{ left }}</pre></td><td><pre>{{ right }}</pre></td></tr>
{% endfor %}</table>
{% endfor %}
</body></html>
"""


@dataclasses.dataclass
class Loaded:
    """The results of a batch as :func:`load_results` reads them.

    Attributes:
        results: the latest result per (student, lesson).
        skipped_lines: lines of results.jsonl that could not be read (truncated, another version).
    """

    results: list[LessonResult]
    skipped_lines: int


def load_results(out_dir: Path) -> Loaded:
    """The latest result per (student, lesson) of ``out_dir/results.jsonl``.

    Args:
        out_dir: the ``--out`` folder of ``ros2course grade``.

    Raises:
        CourseError: the folder or its results.jsonl is missing, or holds no complete record.
    """
    out_dir = Path(out_dir)
    path = out_dir / "results.jsonl"
    if not out_dir.is_dir():
        raise CourseError(f"no such folder: {out_dir}", "give the --out folder of `ros2course grade`")
    if not path.is_file():
        raise CourseError(f"no results.jsonl in {out_dir}",
                          "run `ros2course grade SUBMISSIONS --lesson L --out OUTDIR` first")
    read, skipped = read_results_counted(path)
    results = list(latest(read).values())
    if not results:
        raise CourseError(f"{path} holds no complete result", "grade the class again (--resume keeps finished ones)")
    return Loaded(results, skipped)


def _total_seconds(result: LessonResult) -> float | None:
    if result.seconds is not None:
        return float(result.seconds)
    total = result.timings.get("total") if isinstance(result.timings, dict) else None
    return float(total) if isinstance(total, (int, float)) else None


def _fraction(result: LessonResult) -> float:
    return result.score / result.max_score if result.max_score else 0.0


def class_summary(results: list[LessonResult]) -> dict[str, Any]:
    """Numbers about the class, with no student data.

    Args:
        results: one result per student and lesson.

    Returns:
        ``lessons``: lesson -> ``{students, passed, rate, mean}`` (rate and mean score as 0..1);
        ``median_seconds``, ``slowest_seconds``: grading wall times (None without timings);
        ``statuses``: [(status, count)]; ``checks``: one dict per lost check
        (``lesson, id, name, lost, graded, observed, observed_count``), most often lost first.
    """
    per_lesson: dict[str, list[LessonResult]] = collections.defaultdict(list)
    for result in results:
        per_lesson[result.lesson].append(result)
    lessons = {}
    for lesson, rows in sorted(per_lesson.items()):
        passed = sum(1 for r in rows if r.status == Status.PASSED)
        lessons[lesson] = {"students": len(rows), "passed": passed, "rate": passed / len(rows),
                           "mean": statistics.fmean(_fraction(r) for r in rows)}
    times = [t for t in (_total_seconds(r) for r in results) if t is not None]
    lost: dict[tuple[str, str], list[str]] = collections.defaultdict(list)
    names: dict[tuple[str, str], str] = {}
    graded: collections.Counter[tuple[str, str]] = collections.Counter()
    for result in results:
        for check in result.checks:
            key = (result.lesson, check.id)
            names[key] = check.name or check.id
            graded[key] += 1
            if not check.passed:
                lost[key].append(check.observed or "")
    checks = []
    for (lesson, check_id), observed in lost.items():
        common, count = collections.Counter(observed).most_common(1)[0]
        checks.append({"lesson": lesson, "id": check_id, "name": names[(lesson, check_id)], "lost": len(observed),
                       "graded": graded[(lesson, check_id)], "observed": common, "observed_count": count})
    checks.sort(key=lambda row: (-row["lost"], row["lesson"], row["id"]))
    statuses = collections.Counter(r.status.value for r in results)
    return {"lessons": lessons, "median_seconds": statistics.median(times) if times else None,
            "slowest_seconds": max(times) if times else None, "statuses": sorted(statuses.items()),
            "checks": checks}


def _figure(width: float, height: float):
    """A matplotlib Figure (no pyplot: no global state, the Agg/SVG canvases only)."""
    from matplotlib.figure import Figure  # noqa: PLC0415 - only the report needs matplotlib

    return Figure(figsize=(width, height))


def _svg(figure) -> str:
    """``figure`` as an inline ``<svg>`` element (text as text, no date: small and reproducible)."""
    import matplotlib  # noqa: PLC0415 - matplotlib only when a plot is drawn (start time)

    buffer = io.StringIO()
    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": "ros2course"}):
        figure.savefig(buffer, format="svg", metadata={"Date": None})
    text = buffer.getvalue()
    return text[text.index("<svg"):]


def histogram_svg(fractions: list[float]) -> str:
    """The score distribution as an inline SVG element.

    Args:
        fractions: each result's score / max score (0..1).

    Raises:
        ImportError: matplotlib is not installed.
    """
    figure = _figure(6, 2.4)
    axes = figure.add_subplot()
    axes.hist([100 * f for f in fractions], bins=10, range=(0, 100), color="#4a7", edgecolor="white")
    axes.set_xlabel("score (% of max)")
    axes.set_ylabel("results")
    figure.subplots_adjust(left=0.1, right=0.98, bottom=0.2, top=0.95)
    return _svg(figure)


def rate_plot_svg(streams: dict[str, list[float]], period: float, tolerance: float, statistic: str = "mean") -> str:
    """Intervals between consecutive stamps of each stream, with the band the grader accepts.

    Args:
        streams: label -> stamps (seconds, oldest first, relative to the window's start).
        period: the expected period, seconds.
        tolerance: the accepted fraction of ``period`` (0.15 for ±15 %).
        statistic: what the band bounds: the intervals' ``"mean"`` or ``"median"`` (the check's expected text).

    A stream of more than :data:`MAX_POINTS` intervals is drawn as the longest interval of each
    group of consecutive ones (the SVG stays small; a late message still shows).

    Raises:
        ImportError: matplotlib is not installed.
    """
    figure = _figure(5.2, 2.2)
    axes = figure.add_subplot()
    axes.axhspan(period * (1 - tolerance), period * (1 + tolerance), color="#cfc", label=f"accepted {statistic}")
    axes.axhline(period, color="#6a6", linewidth=0.8)
    for label, stamps in streams.items():
        points = [(b, b - a) for a, b in itertools.pairwise(stamps)]
        step = math.ceil(len(points) / MAX_POINTS)
        if step > 1:  # a 500 Hz stream: the longest interval of each group, so a late message still shows
            points = [max(points[i:i + step], key=lambda p: p[1]) for i in range(0, len(points), step)]
        axes.plot([p[0] for p in points], [p[1] for p in points], marker="." if step == 1 else "",
                  linewidth=0.8, label=label[:40])
    axes.set_xlabel("time in the check's window (s)", fontsize=8)
    axes.set_ylabel("interval (s)", fontsize=8)
    axes.tick_params(labelsize=7)
    axes.locator_params(nbins=5)
    axes.legend(fontsize=6, loc="upper right")
    figure.subplots_adjust(left=0.13, right=0.98, bottom=0.2, top=0.95)  # fixed: tight_layout costs 2/3 of a plot
    return _svg(figure)


def joint_plot_svg(topic: str, stamps: list[float], vectors: list[tuple[float, ...]]) -> str:
    """Each component of a vector stream over time: a robot's joint positions as its driver published them.

    Args:
        topic: the stream's topic (the legend names its components ``<topic>[i]``).
        stamps: seconds from the recording's first message, one per vector, oldest first.
        vectors: the numbers of each message (``JointState.position`` in radians, a MultiArray's ``data``).

    A stream of more than :data:`MAX_POINTS` messages is drawn from every n-th one (a 500 Hz stream of
    10 s keeps 400 points per joint); at most 8 components are drawn.

    Raises:
        ImportError: matplotlib is not installed.
    """
    figure = _figure(5.2, 2.2)
    axes = figure.add_subplot()
    step = max(1, math.ceil(len(stamps) / MAX_POINTS))
    width = max((len(v) for v in vectors), default=0)
    for index in range(min(width, 8)):
        points = [(t, v[index]) for t, v in zip(stamps[::step], vectors[::step]) if len(v) > index]
        axes.plot([p[0] for p in points], [p[1] for p in points], linewidth=0.9, label=f"[{index}]")
    axes.set_xlabel(f"time (s) of {topic[:60]}", fontsize=8)
    axes.set_ylabel("value (rad for joints)", fontsize=8)
    axes.tick_params(labelsize=7)
    axes.locator_params(nbins=5)
    axes.legend(fontsize=6, loc="upper right", ncol=4)
    figure.subplots_adjust(left=0.13, right=0.98, bottom=0.2, top=0.95)
    return _svg(figure)


def _href(out_dir: Path, path: Path) -> str:
    """A relative, percent-encoded link from the report to ``path``."""
    return urllib.parse.quote(Path(os.path.relpath(path, out_dir)).as_posix())


def _log_folder(out_dir: Path, result: LessonResult) -> Path | None:
    """The result's log folder: ``OUTDIR/<student>/logs/<lesson>`` (OUTDIR may have moved), else its ``log_dir``."""
    for folder in (out_dir / result.student / "logs" / result.lesson if result.student else None,
                   Path(result.log_dir) if result.log_dir else None):
        if folder is not None and not folder.is_absolute():
            folder = out_dir / folder
        if folder is not None and folder.is_dir():
            return folder
    return None


def _recording(out_dir: Path, result: LessonResult) -> Path | None:
    from ros2course.run.recording import FILE_NAME  # noqa: PLC0415 - start time: the recorder's module only for a report that shows recordings

    folder = _log_folder(out_dir, result)
    if folder is not None and (folder / FILE_NAME).is_file():
        return folder / FILE_NAME
    for check in result.checks:
        if check.evidence and check.evidence.get("recording") and Path(str(check.evidence["recording"])).is_file():
            return Path(str(check.evidence["recording"]))
    return None


def _plots(recording: Path, wanted: list[tuple[str, float, float, str]], vectors: list[str]
           ) -> tuple[list[dict[str, Any]], list[str]]:
    """(plots, notes) from one recording, read once.

    Args:
        wanted: the rate checks to draw: [(check id, period s, tolerance, "mean" or "median")].
        vectors: the vector topics to draw as joint streams (:func:`ros2course.report.evidence.vector_topics`).
    """
    from ros2course.report.evidence import groups, read, within  # noqa: PLC0415 - mcap is only needed here

    try:
        observations, windows = read(recording)
    except CourseError as exc:
        return [], [f"recording not readable: {exc}"]
    by_id = {window.check_id: window for window in windows}
    plots, notes = [], []
    for check_id, period, tolerance, statistic in wanted:
        window = by_id.get(check_id)
        if window is None:
            notes.append(f"{check_id}: the recording holds no window for this check")
            continue
        seen = within(observations, window)
        streams = {}
        for (topic, source), items in sorted(groups(seen).items(), key=lambda kv: -len(kv[1]))[:MAX_STREAMS]:
            if len(items) >= 2:
                streams[f"{topic} {source}".strip()] = [(o.stamp_ns - window.start_ns) * 1e-9 for o in items]
        if not streams:
            notes.append(f"{check_id}: fewer than two messages in its window, nothing to plot")
            continue
        caption = (f"{check_id}: interval between messages ({', '.join(streams)}); green band: the {statistic} period "
                   f"{period:.3f} s ± {tolerance:.0%} the grader accepts; observed {window.observed}")
        plots.append({"svg": rate_plot_svg(streams, period, tolerance, statistic), "caption": caption})
    origin = observations[0].stamp_ns if observations else 0
    for topic in vectors[:MAX_STREAMS]:
        items = [o for o in observations if o.topic == topic and o.values]
        if len(items) < 2:
            notes.append(f"{topic}: fewer than two messages recorded, no joint plot")
            continue
        plots.append({"svg": joint_plot_svg(topic, [(o.stamp_ns - origin) * 1e-9 for o in items],
                                            [o.values for o in items]),
                      "caption": f"{topic}: {len(items)} messages as the grader received them, each value "
                                 f"over time ({len(items[0].values)} per message)"})
    return plots, notes


def _students(out_dir: Path, results: list[LessonResult], max_plots: int) -> list[dict[str, Any]]:
    """One dict per result for the template: checks, links, and plots (failed rate checks first, capped)."""
    ordered = sorted(results, key=lambda r: (r.student, r.lesson))
    recordings = {id(r): _recording(out_dir, r) for r in ordered}
    # the rate checks that could be drawn: the lost ones first, then the others
    candidates = []
    for r in ordered:
        if recordings[id(r)] is None:
            continue
        for check in r.checks:
            band = RATE_BAND.search(check.expected or "")
            if band and not check.skipped:
                period = float(band.group(2)) / (1000 if band.group(3) == "ms" else 1)
                candidates.append((check.passed, r.student, r.lesson, id(r), check.id, period,
                                   float(band.group(4)) / 100, band.group(1)))
    candidates.sort(key=lambda c: c[:3])
    chosen: dict[int, list[tuple[str, float, float, str]]] = collections.defaultdict(list)
    for candidate in candidates[:max_plots]:
        chosen[candidate[3]].append(candidate[4:])
    left_out = collections.Counter(c[3] for c in candidates[max_plots:])
    # joint streams (a robot driver's JointState): failed results first, as many as rate plots at most
    from ros2course.report.evidence import vector_topics  # noqa: PLC0415 - mcap is only needed here

    streams = sorted((r.status == Status.PASSED, r.student, r.lesson, id(r), topics) for r in ordered
                     if recordings[id(r)] is not None and (topics := vector_topics(recordings[id(r)])))
    joints = {c[3]: c[4] for c in streams[:max_plots]}
    left_out.update(c[3] for c in streams[max_plots:])
    out = []
    for index, r in enumerate(ordered):
        recording = recordings[id(r)]
        logs = _log_folder(out_dir, r)
        plots, notes = [], []
        wanted = bool(chosen.get(id(r)) or joints.get(id(r)))
        if wanted and recording.stat().st_size > MAX_RECORDING_BYTES:
            notes.append(f"plots not drawn: the recording is over {MAX_RECORDING_BYTES / 1e6:g} MB "
                         "(`ros2course evidence` or Foxglove open it)")
        elif wanted:
            try:
                plots, notes = _plots(recording, chosen.get(id(r), []), joints.get(id(r), []))
            except Exception as exc:  # noqa: BLE001 - a plot that fails never costs the report
                notes.append(f"plots not drawn: {type(exc).__name__}: {exc}")
        if left_out.get(id(r)):
            notes.append(f"{left_out[id(r)]} plot(s) not drawn (a report draws at most {max_plots} of each kind): "
                         f"`ros2course evidence` on the recording shows them")
        if recording is None and r.checks:
            notes.append("no recording for this result: nothing measured on a ROS graph was kept")
        out.append({"anchor": f"s{index}", "student": r.student or "(no id)", "lesson": r.lesson,
                    "status": r.status.value, "passed": r.status == Status.PASSED, "score": f"{r.score:g}",
                    "max_score": f"{r.max_score:g}", "seconds": _total_seconds(r), "message": r.message,
                    "hint": r.hint, "checks": r.checks, "logs": _href(out_dir, logs) if logs else "",
                    "recording": _href(out_dir, recording) if recording else "", "plots": plots,
                    "plot_notes": notes})
    return out


def _similarity(results: list[LessonResult], similarity: bool, exclude_reference: bool,
                submissions: Path | None) -> dict[str, Any]:
    """The "similar submissions" section: ``{note, pairs}``, the note saying in one line what was compared, what
    was left out, and each flagged pair's size, or why nothing was compared.

    Args:
        submissions: the folder to compare; None: none given nor recorded by the run (:func:`write_report`);
            a path that is no folder: the folder the run recorded in ``run.json``, gone since.
    """
    if not similarity:
        return {"note": "not computed (--no-similarity)", "pairs": []}
    if submissions is None:
        return {"note": "not computed: give the submissions folder (--submissions SUBMISSIONS): the run did not "
                        "record its submissions folder", "pairs": []}
    if not Path(submissions).is_dir():
        return {"note": f"not computed: the submissions folder {submissions} recorded by the run is gone "
                        "(give --submissions SUBMISSIONS)", "pairs": []}
    try:
        from ros2course.report.similarity import (  # noqa: PLC0415 - the similarity module only when similarity is asked for
            MIN_SHARED_TOKENS,
            THRESHOLD,
            common_limit,
            similar_pairs,
        )
        comparison = similar_pairs(results, submissions, exclude_reference=exclude_reference)
    except ImportError as exc:
        return {"note": f"not computed: {exc}", "pairs": []}
    if not any(count >= 2 for count in comparison.students.values()):
        return {"note": f"not computed: fewer than two students' sources found in {submissions}", "pairs": []}
    generated = (f"what `ros2 pkg create` writes ({comparison.generated_files} files rendered from "
                 f"{comparison.generated_from})" if comparison.generated_files else
                 f"not what `ros2 pkg create` writes ({comparison.generated_from}): it counts only as common code")
    left = ("the course's starter files" + (" and reference solutions" if exclude_reference else "")
            + f" ({comparison.boilerplate_files} files) and {generated} left out; code found in more than "
            + ", ".join(f"{common_limit(n)} of the {n} students of {lesson}" for lesson, n in comparison.students.items())
            + " is common (a third of a section, 2 to 10, or a tenth of a larger class: Moss's -m) and left out too")
    sizes = "; ".join(f"{pair.first} / {pair.second}: {pair.shared_tokens}" for pair in comparison.pairs[:MAX_PAIRS])
    note = (f"copydetect (winnowing) per lesson over {comparison.files} file(s) with code of their own; {left}; "
            f"pairs at least {THRESHOLD:.0%} alike over what is left and sharing at least {MIN_SHARED_TOKENS} "
            f"tokens of it (about 8 lines): {len(comparison.pairs)}"
            + (f" (the first {MAX_PAIRS} shown)" if len(comparison.pairs) > MAX_PAIRS else "")
            + (f"; shared beyond boilerplate, in copydetect tokens (~15 a line of Python): {sizes}" if sizes else "")
            + f"; {comparison.seconds:.1f} s. Similarity only flags; it never changes a grade.")
    return {"note": note, "pairs": comparison.pairs[:MAX_PAIRS]}


def render_report(out_dir: Path, *, similarity: bool = True, exclude_reference: bool = True,
                  submissions: Path | None = None, max_plots: int = MAX_PLOTS) -> str:
    """The report's HTML text, with the arguments of :func:`write_report` (nothing is written).

    Raises:
        CourseError: ``out_dir`` or its results.jsonl is missing or holds no complete record.
    """
    import jinja2  # noqa: PLC0415 - only the report needs it

    out_dir = Path(out_dir)
    loaded = load_results(out_dir)
    results = loaded.results
    summary = class_summary(results)
    try:
        histogram = histogram_svg([_fraction(r) for r in results])
    except ImportError as exc:
        histogram = f"(histogram not drawn: {exc})"
    students = _students(out_dir, results, max_plots)
    anchors = {(s["student"], s["lesson"]): s["anchor"] for s in students}
    timed = [(t, r.student) for r in results if (t := _total_seconds(r)) is not None]
    isolation = collections.Counter(
        ", ".join(f"{k}={v}" for k, v in sorted(r.isolation.items())) if r.isolation else "unknown (not recorded)"
        for r in results)
    unfinished = [{"student": r.student, "lesson": r.lesson, "status": r.status.value, "message": r.message,
                   "hint": r.hint, "anchor": anchors.get((r.student or "(no id)", r.lesson), "")}
                  for r in sorted(results, key=lambda r: (r.student, r.lesson))
                  if r.status in (Status.NOT_GRADABLE, Status.GRADER_ERROR)]
    environment = jinja2.Environment(autoescape=True, undefined=jinja2.StrictUndefined)
    template = environment.from_string(_TEMPLATE)
    return template.render(
        title=out_dir.resolve().name, style=jinja2.utils.markupsafe.Markup(_STYLE), records=len(results),
        skipped_lines=loaded.skipped_lines,
        histogram=jinja2.utils.markupsafe.Markup(histogram) if histogram.startswith("<svg") else histogram,
        lessons=summary["lessons"], statuses=summary["statuses"], median=summary["median_seconds"],
        slowest=summary["slowest_seconds"], slowest_who=max(timed)[1] if timed else "",
        isolation=isolation.most_common(), unfinished=unfinished, checks=summary["checks"],
        students=[dict(s, plots=[dict(p, svg=jinja2.utils.markupsafe.Markup(p["svg"])) for p in s["plots"]])
                  for s in students],
        similarity=_similarity(results, similarity, exclude_reference, submissions),
        adjustments=adjustments_section(out_dir), regrades=regrades_section(out_dir))


def write_report(out_dir: Path, *, similarity: bool = True, exclude_reference: bool = True,
                 submissions: Path | None = None, max_plots: int = MAX_PLOTS) -> Path:
    """Write ``out_dir/report.html`` from ``out_dir/results.jsonl``, the recordings and the submissions.

    Args:
        out_dir: the ``--out`` folder of ``ros2course grade``.
        similarity: compare the submissions (:mod:`ros2course.report.similarity`) and list similar pairs.
        exclude_reference: leave the reference solution out of the comparison (the starter always is).
        submissions: the submissions folder graded (folders or archives); None: the folder the run recorded
            (``{"submissions": "<absolute path>"}`` in ``OUTDIR/run.json``, the batch runner writes it), if
            it is still there; else the similarity section says in one line why it is absent.
        max_plots: rate plots drawn at most (failed checks first).

    Returns:
        The path of the report.

    Raises:
        CourseError: ``out_dir`` or its results.jsonl is missing or holds no complete record.
    """
    if submissions is None and similarity:
        import json  # noqa: PLC0415 - only with similarity

        try:
            recorded = json.loads((Path(out_dir) / "run.json").read_text(encoding="utf-8")).get("submissions")
        except (OSError, ValueError, AttributeError):  # no run.json (an older run), unreadable, not an object
            recorded = None
        if isinstance(recorded, str) and recorded.strip():
            # a folder gone since reaches _similarity, which says so; a relative path is read from OUTDIR
            submissions = Path(out_dir) / Path(recorded).expanduser()
    text = render_report(out_dir, similarity=similarity, exclude_reference=exclude_reference,
                         submissions=submissions, max_plots=max_plots)
    path = Path(out_dir) / "report.html"
    atomic_write_text(path, text)
    return path


def write_markdown(out_dir: Path) -> str:
    """A Markdown summary of the class and the checks, with no student names or data.

    Args:
        out_dir: the ``--out`` folder of ``ros2course grade``.

    Returns:
        The Markdown text (pipes and newlines in texts made table-safe).

    Raises:
        CourseError: ``out_dir`` or its results.jsonl is missing or holds no complete record.
    """
    results = load_results(Path(out_dir)).results
    summary = class_summary(results)

    def cell(text: object) -> str:
        return str(text).replace("|", "\\|").replace("\n", " ")

    lines = ["# Class report", "", "## The class", "", "| lesson | students | passed | pass rate | mean score |",
             "|---|---|---|---|---|"]
    for lesson, row in summary["lessons"].items():
        lines.append(f"| {cell(lesson)} | {row['students']} | {row['passed']} | {100 * row['rate']:.0f}% "
                     f"| {100 * row['mean']:.0f}% |")
    lines += ["", "Statuses: " + ", ".join(f"{k}: {v}" for k, v in summary["statuses"])]
    if summary["median_seconds"] is not None:
        lines.append(f"Grading time: median {summary['median_seconds']:.1f} s, "
                     f"slowest {summary['slowest_seconds']:.1f} s")
    lines += _late_markdown(Path(out_dir))
    lines += ["", "## The checks", "", "| lesson | check | lost by |", "|---|---|---|"]
    for row in summary["checks"]:
        lines.append(f"| {cell(row['lesson'])} | {cell(row['name'])} | {row['lost']} of {row['graded']} |")
    return "\n".join(lines) + "\n"


def adjustments_section(out_dir: Path, class_path: Path | None = None) -> dict[str, Any] | None:
    """The report's "Deadlines and late policy" section: raw score, adjusted score and reason per result.

    Args:
        out_dir: the ``--out`` folder of ``ros2course grade``.
        class_path: the class file (:mod:`ros2course.report.term`); None: ``OUTDIR/class.yaml``.

    Returns:
        None when there is no class file (the section is left out); else ``{note, rows}`` with
        ``rows`` of ``{student, lesson, raw, max, score, reason}``. A class file that cannot be
        used gives a note saying why and no rows: the report is never lost to it.
    """
    from ros2course.report.term import CLASS_FILE, adjust_out_dir  # noqa: PLC0415 - start time: pydantic (the class file's model) only when a class file is read

    out_dir = Path(out_dir)
    path = Path(class_path) if class_path is not None else out_dir / CLASS_FILE
    if not path.is_file():
        return None
    try:
        book = adjust_out_dir(out_dir, path)
    except CourseError as exc:
        return {"note": f"the class file was not applied: {exc.message}" + (f" ({exc.hint})" if exc.hint else ""),
                "rows": []}
    late = sum(1 for a in book.adjusted if a.late)
    rows = [{"student": a.student or "(no id)", "lesson": a.lesson, "raw": f"{a.raw_score:g}",
             "max": f"{a.max_score:g}", "score": f"{a.score:g}", "reason": a.reason} for a in book.adjusted]
    return {"note": f"Due dates, extensions and late policy of {path.name}; {late} late submission(s). "
                    "`ros2course export OUTDIR --format canvas|moodle|csv` exports the adjusted scores.",
            "rows": rows}


def _late_markdown(out_dir: Path) -> list[str]:
    """Lines of late submissions per lesson (no student data) when ``OUTDIR/class.yaml`` applies; else none."""
    from ros2course.report.term import CLASS_FILE, adjust_out_dir, late_counts  # noqa: PLC0415 - start time: pydantic (the class file's model) only when a class file is read

    if not (out_dir / CLASS_FILE).is_file():
        return []
    try:
        counts = late_counts(adjust_out_dir(out_dir).adjusted)
    except CourseError:  # its message may name a student: none in the summary
        return ["", "Late submissions: not counted (class.yaml has a problem: `ros2course export OUTDIR` says which)"]
    return ["", "Late submissions (class.yaml): " + ", ".join(f"{k}: {v}" for k, v in counts.items())]


def regrades_section(out_dir: Path) -> dict[str, Any] | None:
    """The report's "Regrades" section from ``OUTDIR/regrades.jsonl`` (``ros2course.batch.provenance``): per
    regraded row the old and new score, the checks whose points moved, why, and the grader fingerprints
    before and after; None when nothing was ever regraded (the section is left out)."""
    changes = read_regrades(Path(out_dir))
    if not changes:
        return None

    def score(change: dict[str, Any]) -> str:
        kept = change.get("kept")
        return (f"{change.get('old_score', 0):g} kept (the regrade failed: {kept})" if kept
                else f"{change.get('old_score', 0):g} -> {change.get('new_score', 0):g} of {change.get('max_score', 0):g}")

    rows = [{"student": c.get("student", ""), "lesson": c.get("lesson", ""), "score": score(c),
             "checks": ", ".join(f"{cid} {old} -> {new}" for cid, (old, new) in (c.get("checks") or {}).items()) or "none",
             "why": c.get("why", ""),
             "graders": f"{(c.get('old') or {}).get('grader', '?')} -> {(c.get('new') or {}).get('grader', '?')}"}
            for c in changes if isinstance(c, dict)]
    moved = collections.Counter(c.get("direction", "") for c in changes if isinstance(c, dict))
    return {"note": f"{len(rows)} regraded row(s) (grade --regrade / --only): {moved['up']} up, {moved['down']} down, "
                    f"{moved['same']} unchanged, {moved['kept']} kept because the regrade failed. Each row of "
                    "results.jsonl names the grader fingerprint and submission digest it was graded with.",
            "rows": rows}
