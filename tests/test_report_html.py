"""``ros2course report``: the instructor's HTML report, its Markdown summary and similar submissions (issue 21).

One real batch (``workspace-setup``: no ROS nodes, ~3 s) is graded once for the module; rows a
batch also writes (a timeout, a node printing ``<script>``, a rate check with its recording), a
row of an older version, one of an unknown version and a truncated last line are appended to its
``results.jsonl``. Everything else reads that folder.
"""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ros2course.errors import CourseError
from ros2course.grade.results import CheckResult, LessonResult, Status
from ros2course.lesson import content_root
from ros2course.report.html import load_results, render_report, write_markdown, write_report
from ros2course.report.similarity import similar_pairs

LESSON = "workspace-setup"
MINIMALIST = "python-minimalist-package"
STARTER = content_root() / "chapters" / "python-minimalist-package" / "starter" / "python" / "minimalist_package"
REFERENCE = content_root() / "solutions" / "python" / "minimalist_package"
#: What a hostile node prints: it would retitle the page and write a marker into the DOM if it ran.
INJECTED = "<script>document.title='PWNED';document.write('INJECTED-RAN')</script><img src=x onerror=alert(1)>"
RATE_EXPECTED = "2.00 Hz: mean period 0.500 s ± 15%, over at least 5 intervals"

OWN_CODE = '''
import math


def trajectory(points, speed):
    """Time-stamped waypoints along a polyline at constant speed."""
    out = []
    elapsed = 0.0
    previous = points[0]
    for point in points:
        distance = math.dist(previous, point)
        elapsed += distance / speed
        out.append((elapsed, point))
        previous = point
    return out


def smooth(values, window):
    result = []
    for index in range(len(values)):
        start = max(0, index - window)
        chunk = values[start:index + 1]
        result.append(sum(chunk) / len(chunk))
    return result


def clamp_all(values, low, high):
    return [min(high, max(low, value)) for value in values]
'''

OTHER_CODE = [
    '''
class Counter:
    def __init__(self):
        self.count = 0
        self.history = {}

    def bump(self, key):
        self.count += 1
        self.history.setdefault(key, []).append(self.count)
        return self.history[key]

    def report(self):
        return sorted((len(v), k) for k, v in self.history.items())
''',
    '''
def parse_config(text):
    settings = {}
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line or "=" not in line:
            continue
        name, value = (part.strip() for part in line.split("=", 1))
        settings[name.lower()] = int(value) if value.isdigit() else value
    return settings
''',
    '''
def histogram(samples, bins=10):
    low, high = min(samples), max(samples)
    width = (high - low) / bins or 1.0
    counts = [0] * bins
    for sample in samples:
        slot = min(bins - 1, int((sample - low) / width))
        counts[slot] += 1
    return [(low + slot * width, count) for slot, count in enumerate(counts)]
''',
    '''
async def gather_replies(client, requests, timeout=2.0):
    replies = {}
    while requests:
        name, payload = requests.pop()
        future = client.call_async(payload)
        try:
            replies[name] = await asyncio.wait_for(future, timeout)
        except asyncio.TimeoutError:
            replies[name] = None
    return replies
''',
]


def _recording(path: Path, check_id: str) -> None:
    """An ``observed.mcap`` written by the grader's own recorder: /chatter at ~2 Hz, one slow gap."""
    from std_msgs.msg import String

    from ros2course.run.recording import CHECKS_METADATA, Recorder

    recorder = Recorder(path)
    start = stamp = 1_700_000_000_000_000_000
    for n, gap in enumerate([0.5, 0.5, 0.52, 1.4, 0.5, 0.49, 0.5]):
        stamp += int(gap * 1e9)
        recorder.write(0, "/chatter", String(data=f"hello {n}"), publish_ns=stamp)
    recorder.metadata(CHECKS_METADATA, {check_id: json.dumps({"passed": False, "observed": "1.67 Hz",
                                                              "start_ns": start, "end_ns": stamp})})
    recorder.close()


def _check(check_id: str, passed: bool, observed: str, expected: str = "as in the lesson") -> CheckResult:
    return CheckResult(id=check_id, name=f"check {check_id}", points=1.0 if passed else 0.0, max_points=1.0,
                       passed=passed, observed=observed, expected=expected, hint="read the lesson")


@pytest.fixture(scope="module")
def graded(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """(OUTDIR, SUBMISSIONS) of a real batch plus the appended rows (see the module's docstring).

    Graded once per test run: pytest-xdist's workers share it through their common temporary
    folder, under a lock (tests only read it; reports are rendered to strings or to copies).
    """
    import fcntl

    shared = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        shared = shared.parent  # the run's folder, common to its workers
    root = shared / "report-html-class"
    root.mkdir(exist_ok=True)
    with open(root / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (root / "done").exists():
            _grade_the_class(root)
            (root / "done").touch()
    return root / "out", root / "subs"


def _grade_the_class(root: Path) -> None:
    from ros2course.batch.runner import run_batch

    subs, out = root / "subs", root / "out"
    for name in ("eve_copy", "fay_copy", "gus_other", "hal_other"):
        (subs / name / "src" / "pkg").mkdir(parents=True)
    (subs / "eve_copy" / "src" / "pkg" / "motion.py").write_text(OWN_CODE)
    (subs / "fay_copy" / "src" / "pkg" / "motion.py").write_text(OWN_CODE.replace("elapsed", "t_total"))
    for name, own in zip(("gus_other", "hal_other"), OTHER_CODE):  # alike only in an earlier lesson's starter
        shutil.copytree(STARTER, subs / name / "src" / "pkg" / "minimalist_package")
        (subs / name / "src" / "pkg" / "own.py").write_text(own)
    # graded, as check grades it: workspace-setup's hand-in is the workspace folder, and one without src/ loses
    # src_folder (batch.archive.prepare's packages_needed); the broken zip is the class's not-gradable hand-in
    (subs / "bob_nosrc").mkdir()
    (subs / "cy_broken.zip").write_bytes(b"not a zip")
    run_batch(subs, [LESSON], out, jobs=2)
    log_dir = out / "rita_rate" / "logs" / LESSON
    log_dir.mkdir(parents=True)
    _recording(log_dir / "observed.mcap", "rate")
    rows = [
        LessonResult(LESSON, 1, 2, Status.FAILED, [_check("built", True, "built"), _check("rate", False, "1.67 Hz",
                                                                                          RATE_EXPECTED)],
                     student="rita_rate", seconds=9.0, log_dir=str(log_dir)),
        LessonResult(LESSON, 1, 2, Status.FAILED, [_check("built", True, "built"), _check("prints", False, INJECTED)],
                     student="sam_script", seconds=7.0),
        LessonResult.unfinished(LESSON, Status.NOT_GRADABLE, "timed out after 300 s",
                                "the submission was stopped: a node that never ends or a build that hangs?", 2),
    ]
    rows[2].student = "tim_timeout"
    with open(out / "results.jsonl", "a", encoding="utf-8") as handle:
        for row in rows:
            handle.write(json.dumps(row.to_record()) + "\n")
        # an older version's row: no timings, isolation, log_dir or seconds
        handle.write(json.dumps({"student": "olga_old", "lesson": LESSON, "score": 1, "max_score": 2,
                                 "status": "failed", "checks": [{"id": "built", "passed": False}]}) + "\n")
        handle.write(json.dumps({"student": "una_unknown", "lesson": LESSON, "status": "error", "timings": 3}) + "\n")
        handle.write('{"student": "zed_cut", "lesson": "workspace-setup", "sco')  # a batch killed mid-line


def test_report_from_a_real_batch(graded: tuple[Path, Path]) -> None:
    out, subs = graded
    text = render_report(out, submissions=subs)
    for part in ('id="class"', 'id="checks"', 'id="students"', 'id="similar"', "<svg", "not gradable",
                 "timed out after 300 s", "unreadable .zip", "bob_nosrc", "olga_old", "2 line(s) could not be read",
                 "Isolation in effect", "Grading time: median"):
        assert part in text, part
    assert "zed_cut" not in text and "una_unknown" not in text
    # each student: their checks, links to their logs, their recording's plot (or that there is none)
    assert 'href="eve_copy/logs/workspace-setup"' in text
    rita = text[text.index("rita_rate: workspace-setup"):]
    rita = rita[:rita.index("</section>")]
    assert 'href="rita_rate/logs/workspace-setup/observed.mcap"' in rita
    assert rita.count("<svg") == 1 and "mean period 0.500 s ± 15%" in rita and "/chatter" in rita
    sam = text[text.index("sam_script: workspace-setup"):]
    assert "no recording" in sam[:sam.index("</section>")]
    # the checks, most often lost first
    checks = text[text.index('id="checks"'):text.index('id="students"')]
    assert "lost by" in checks
    # escaping: nothing student-controlled became markup, no external URL, no script at all
    assert "&lt;script&gt;document.title=" in text and "<script" not in text and "onerror=alert" not in text.replace(
        "onerror=alert(1)&gt;", "")
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", text)
    # similar submissions: the near-copies flagged, students alike only in the starter not
    similar = text[text.index('id="similar"'):]
    assert "eve_copy / fay_copy" in similar and "trajectory" in similar
    assert "gus_other" not in similar and "starter files and reference solutions (" in similar


def test_report_without_similarity_or_sources_says_so(graded: tuple[Path, Path], tmp_path: Path) -> None:
    out, _subs = graded
    assert "not computed (--no-similarity)" in render_report(out, similarity=False)
    assert "give the submissions folder" in render_report(out, submissions=None, max_plots=0)
    assert "fewer than two students" in render_report(out, submissions=tmp_path, max_plots=0)


def test_plots_are_capped_and_say_so(graded: tuple[Path, Path]) -> None:
    text = render_report(graded[0], similarity=False, max_plots=0)
    assert "<figure>" not in text and "1 plot(s) not drawn (a report draws at most 0 of each kind)" in text


def test_similarity_leaves_the_reference_out_unless_asked(tmp_path: Path) -> None:
    """Two students who both handed in the reference solution, two the starter, each plus code of their own."""
    subs = tmp_path / "subs"
    results = []
    for name, own, given in zip(("ann", "ben", "cal", "dan"), OTHER_CODE, (REFERENCE, REFERENCE, STARTER, STARTER)):
        shutil.copytree(given, subs / name / "python" / "minimalist_package")
        (subs / name / "python" / "minimalist_package" / "own.py").write_text(own)
        results.append(LessonResult(MINIMALIST, 1, 2, Status.FAILED, [], student=name))
    shutil.make_archive(str(subs / "ben"), "zip", subs / "ben")  # archives are read in memory too
    shutil.rmtree(subs / "ben")
    excluded = similar_pairs(results, subs)
    assert excluded.students == {MINIMALIST: 4} and excluded.pairs == []
    included = similar_pairs(results, subs, exclude_reference=False)
    assert [(p.first, p.second) for p in included.pairs] == [("ann", "ben")] and included.pairs[0].score > 0.9


def test_bad_rows_are_counted_not_fatal(graded: tuple[Path, Path]) -> None:
    loaded = load_results(graded[0])
    assert loaded.skipped_lines == 2
    assert {r.student for r in loaded.results} >= {"olga_old", "eve_copy", "tim_timeout", "rita_rate"}


def test_markdown_has_the_class_and_no_student_data(graded: tuple[Path, Path]) -> None:
    out, subs = graded
    markdown = write_markdown(out)
    assert "## The checks" in markdown and "| workspace-setup |" in markdown
    for name in [entry.name.split(".")[0] for entry in subs.iterdir()] + ["rita_rate", "sam_script", "PWNED"]:
        assert name not in markdown, name


def test_gradebook_of_the_batch_has_totals(graded: tuple[Path, Path]) -> None:
    rows = list(csv.DictReader(open(graded[0] / "gradebook.csv", encoding="utf-8")))
    assert rows and all(r["total"] == r["score"] and r["total_max"] == r["max_score"] for r in rows)


def test_missing_results_raise(tmp_path: Path) -> None:
    with pytest.raises(CourseError):
        write_report(tmp_path)
    (tmp_path / "results.jsonl").write_text("")
    with pytest.raises(CourseError):
        write_markdown(tmp_path)


def test_cli(graded: tuple[Path, Path], tmp_path: Path) -> None:
    out, subs = graded
    copy = tmp_path / "moved"
    shutil.copytree(out, copy)  # an OUTDIR moved elsewhere still links its logs
    proc = subprocess.run([sys.executable, "-m", "ros2course", "report", str(copy), "--submissions", str(subs),
                           "--no-exclude-reference"], check=False, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    text = (copy / "report.html").read_text(encoding="utf-8")
    assert 'href="rita_rate/logs/workspace-setup/observed.mcap"' in text and "eve_copy / fay_copy" in text
    assert "starter files (" in text and "reference solutions" not in text
    proc = subprocess.run([sys.executable, "-m", "ros2course", "report", str(out), "--format", "md"],
                          check=False, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and "# Class report" in proc.stdout
    for target, args in ((tmp_path / "nowhere", []), (out, ["--format", "pdf"]), (out, ["--submissions", "/no"])):
        proc = subprocess.run([sys.executable, "-m", "ros2course", "report", str(target), *args], check=False, capture_output=True,
                              text=True, timeout=60)
        assert proc.returncode != 0 and "Traceback" not in proc.stderr and "error" in proc.stderr, proc.stderr


def test_headless_browser_renders_and_runs_no_injected_script(graded: tuple[Path, Path], tmp_path: Path) -> None:
    """Chromium (Debian's package) opens the report: no script error, the injected <script> did not run."""
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        pytest.skip("chromium is not installed (Debian: apt-get install chromium; .ci/run installs it as root)")
    out, _subs = graded
    path = tmp_path / "report.html"
    path.write_text(render_report(out, similarity=False), encoding="utf-8")
    base = [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-extensions",
            f"--user-data-dir={tmp_path / 'profile'}", "--enable-logging=stderr", "--v=0",
            "--virtual-time-budget=3000"]
    dom = subprocess.run([*base, "--dump-dom", path.as_uri()], capture_output=True, text=True, timeout=90,
                         check=False)
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert "<title>Class report:" in dom.stdout and "PWNED" not in dom.stdout.split("</title>")[0]
    assert "INJECTED-RAN" not in dom.stdout.replace("document.write('INJECTED-RAN')", "")
    assert "&lt;script&gt;document.title='PWNED'" in dom.stdout  # shown as text
    assert "sam_script" in dom.stdout
    # the report has no script: any console message (a script error, a Content-Security-Policy
    # violation such as an injected inline script blocked) is a fault
    errors = [line for line in dom.stderr.splitlines()
              if re.search(r":CONSOLE|Uncaught|Content Security Policy|Refused to", line)]
    assert not errors, errors
    shot = tmp_path / "report.png"
    done = subprocess.run([*base, "--window-size=1200,900", f"--screenshot={shot}", path.as_uri()],
                          check=False, capture_output=True, text=True, timeout=90)
    assert done.returncode == 0 and shot.is_file() and shot.stat().st_size > 10_000, done.stderr[-2000:]


def test_a_joint_stream_is_drawn_from_the_recording(tmp_path: Path) -> None:
    """A robot driver's JointState stream (the sas lesson's) is plotted per joint, from the recording alone."""
    from sensor_msgs.msg import JointState

    from ros2course.run.recording import Recorder

    out = tmp_path / "out"
    log_dir = out / "jo_joints" / "logs" / "sas-robot-driver"
    log_dir.mkdir(parents=True)
    recorder = Recorder(log_dir / "observed.mcap")
    stamp = 1_700_000_000_000_000_000
    for n in range(1000):  # 2 s at 500 Hz: drawn from every 3rd message
        stamp += 2_000_000
        recorder.write(0, "/myrobot_1/get/joint_states",
                       JointState(name=["j1", "j2"], position=[0.001 * n, -0.002 * n]), publish_ns=stamp)
    recorder.close()
    row = LessonResult("sas-robot-driver", 1, 2, Status.FAILED,
                       [_check("built", True, "built"), _check("follows", False, "2 of 3 targets reached")],
                       student="jo_joints", seconds=20.0, log_dir=str(log_dir))
    (out / "results.jsonl").write_text(json.dumps(row.to_record()) + "\n")
    text = render_report(out, similarity=False)
    section = text[text.index("jo_joints"):]
    assert "/myrobot_1/get/joint_states: 1000 messages" in section and "2 per message" in section
    assert section.count("<svg") >= 1 and "[1]" in section
