"""Similar submissions flag only what is worth a look, and the report remembers its submissions (issue 39).

The class: a lab section of five ``print-forever-node`` submissions, each a real ament_python package
made by ``ros2 pkg create --build-type ament_python --node-name sample_python_node`` (ros2pkg's own
create verb, run in a subprocess, when ros2pkg is found; else the course's own generated package
stands in). ann and ben add the same 40 lines of their own to the sample node; dan's submission is a
byte copy of cal's; cal and eve wrote their own code. Exactly two pairs are worth a look: ann / ben
and cal / dan. Nothing here starts ROS.
"""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ros2course.grade.results import LessonResult, Status
from ros2course.lesson import content_root
from ros2course.report import similarity
from ros2course.report.html import write_report
from ros2course.report.similarity import MIN_SHARED_TOKENS, common_limit, compare_sources, similar_pairs

pytest.importorskip("copydetect")

LESSON = "print-forever-node"
NODE = "sample_python_node"

#: The 40 lines ann and ben both add to the sample node.
SHARED_40 = '''

import math


class Odometry:
    """Dead reckoning of a differential drive from wheel ticks."""

    def __init__(self, ticks_per_turn, radius, track):
        self.metres_per_tick = 2 * math.pi * radius / ticks_per_turn
        self.track = track
        self.x = self.y = self.heading = 0.0
        self.last = None

    def update(self, left_ticks, right_ticks):
        if self.last is None:
            self.last = (left_ticks, right_ticks)
            return self.pose()
        left = (left_ticks - self.last[0]) * self.metres_per_tick
        right = (right_ticks - self.last[1]) * self.metres_per_tick
        self.last = (left_ticks, right_ticks)
        forward = (left + right) / 2
        turn = (right - left) / self.track
        self.x += forward * math.cos(self.heading + turn / 2)
        self.y += forward * math.sin(self.heading + turn / 2)
        self.heading = math.atan2(math.sin(self.heading + turn), math.cos(self.heading + turn))
        return self.pose()

    def pose(self):
        return round(self.x, 3), round(self.y, 3), round(self.heading, 3)


def drive(odometry, samples):
    poses = []
    for left, right in samples:
        poses.append(odometry.update(left, right))
    return poses


def report(poses):
    for index, pose in enumerate(poses):
        print(f'{index}: x={pose[0]} y={pose[1]} heading={pose[2]}')
'''

#: cal's own code (dan hands in a byte copy of cal's submission).
CAL_OWN = '''

import time


def countdown(start, pause):
    remaining = start
    while remaining > 0:
        print(f'{remaining} left')
        time.sleep(pause)
        remaining -= 1
    return 'lift-off'


def histogram(words):
    counts = {}
    for word in words:
        key = word.lower().strip('.,;')
        counts[key] = counts.get(key, 0) + 1
    longest = max(len(key) for key in counts)
    lines = []
    for key, count in sorted(counts.items(), key=lambda item: -item[1]):
        lines.append(key.ljust(longest) + ' ' + '#' * count)
    return '\\n'.join(lines)
'''

#: eve's own code.
EVE_OWN = '''

import random


class Dice:
    def __init__(self, sides=6, seed=None):
        self.sides = sides
        self.rng = random.Random(seed)
        self.history = []

    def roll(self, times=1):
        values = [self.rng.randint(1, self.sides) for _ in range(times)]
        self.history.extend(values)
        return values

    def mean(self):
        if not self.history:
            raise ValueError('roll first')
        return sum(self.history) / len(self.history)


def play(rounds, players):
    scores = {player: 0 for player in players}
    dice = Dice(seed=rounds)
    for _ in range(rounds):
        for player in players:
            scores[player] += sum(dice.roll(2))
    return max(scores, key=scores.get), scores
'''


def _ros2pkg_path() -> str | None:
    """A PYTHONPATH entry under which ``ros2pkg`` imports ("" when it already does), or None."""
    if importlib.util.find_spec("ros2pkg") is not None:
        return ""
    from ros2course.ros import underlay  # noqa: PLC0415

    built = underlay.current()
    if built is not None and (built.site_packages / "ros2pkg" / "verb" / "create.py").is_file():
        return str(built.site_packages)
    return None


ROS2PKG = _ros2pkg_path()
needs_ros2pkg = pytest.mark.skipif(ROS2PKG is None, reason="ros2pkg not found (no ROS 2, no underlay built)")

#: ``ros2 pkg create`` for each (destination, package, maintainer, dependencies) of argv[1] (JSON), with
#: ros2pkg's own create verb (ros2cli's ``main`` parses one command per process).
_CREATE = """
import argparse, json, sys
from ros2pkg.verb.create import CreateVerb
for destination, package, maintainer, dependencies in json.loads(sys.argv[1]):
    verb = CreateVerb()
    parser = argparse.ArgumentParser()
    verb.add_arguments(parser, 'ros2')
    args = parser.parse_args(['--build-type', 'ament_python', '--node-name', 'sample_python_node',
                              '--destination-directory', destination, '--maintainer-name', maintainer,
                              '--maintainer-email', maintainer + '@example.com', package,
                              *(['--dependencies', *dependencies] if dependencies else [])])
    failure = verb.main(args=args)
    if failure:
        sys.exit(failure)
"""


def _create_packages(specs: list[tuple[Path, str, str, list[str]]]) -> None:
    """Write each package as ``ros2 pkg create --build-type ament_python --node-name sample_python_node`` would.

    Without ros2pkg the course's own package of the python-node-template lesson (made by that command,
    package ``python_package_with_a_node``) stands in, with a ``test/`` folder of lint tests alike for all.
    """
    if ROS2PKG is not None:
        env = dict(os.environ)
        if ROS2PKG:
            env["PYTHONPATH"] = os.pathsep.join(filter(None, [ROS2PKG, env.get("PYTHONPATH", "")]))
        run = subprocess.run([sys.executable, "-c", _CREATE, json.dumps([(str(d), p, m, deps) for d, p, m, deps in specs])],
                             env=env, capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, run.stdout + run.stderr
        return
    given = content_root() / "chapters" / "python-node-template" / "starter" / "src" / "python_package_with_a_node"
    for destination, _package, _maintainer, _dependencies in specs:
        shutil.copytree(given, destination / given.name)
        for linter in ("copyright", "flake8", "pep257"):
            (destination / given.name / "test").mkdir(exist_ok=True)
            (destination / given.name / "test" / f"test_{linter}.py").write_text(
                f"import pytest\n\n\n@pytest.mark.linter\ndef test_{linter}():\n    rc = run_{linter}(argv=['.', 'test'])\n"
                "    assert rc == 0, 'Found errors'\n")


def _node(workspace: Path) -> Path:
    return next(workspace.glob(f"src/*/*/{NODE}.py"))


def make_class(subs: Path) -> list[LessonResult]:
    """The section of five in ``subs`` (one workspace per student); their results."""
    _create_packages([(subs / "ann" / "src", "ann_odometry", "ann", []),
                      (subs / "ben" / "src", "ben_pkg", "Ben Example", []),
                      (subs / "cal" / "src", "cal_nodes", "cal", []),
                      (subs / "eve" / "src", "eve_pkg", "eve", ["rclpy", "std_msgs"])])
    for student, own in (("ann", SHARED_40), ("ben", SHARED_40), ("cal", CAL_OWN), ("eve", EVE_OWN)):
        node = _node(subs / student)
        node.write_text(node.read_text() + own)
    shutil.copytree(subs / "cal", subs / "dan")  # a byte copy
    return [LessonResult(LESSON, 3, 6, Status.FAILED, [], student=s) for s in ("ann", "ben", "cal", "dan", "eve")]


@pytest.fixture(scope="module")
def section(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[LessonResult]]:
    subs = tmp_path_factory.mktemp("section") / "subs"
    return subs, make_class(subs)


def _pairs(comparison) -> list[tuple[str, str]]:
    return sorted((pair.first, pair.second) for pair in comparison.pairs)


def test_a_section_of_five_gives_exactly_the_two_true_pairs(section) -> None:
    subs, results = section
    comparison = similar_pairs(results, subs)
    assert comparison.students == {LESSON: 5}
    assert _pairs(comparison) == [("ann", "ben"), ("cal", "dan")], comparison.pairs
    by_pair = {(p.first, p.second): p for p in comparison.pairs}
    assert all(p.shared_tokens >= MIN_SHARED_TOKENS and p.score >= 0.8 for p in comparison.pairs)
    assert by_pair["ann", "ben"].files == (f"src/ann_odometry/ann_odometry/{NODE}.py", f"src/ben_pkg/ben_pkg/{NODE}.py") \
        if ROS2PKG is not None else by_pair["ann", "ben"].files[0].endswith(f"{NODE}.py")
    shown = "".join(left for left, _right in by_pair["ann", "ben"].fragments)  # where winnowing cuts varies
    assert "heading" in shown and "Hi from" not in shown  # their own code, not the generated print
    if ROS2PKG is not None:
        assert comparison.generated_files > 10 and "ros2pkg" in comparison.generated_from


def test_the_old_rules_flagged_every_pair_of_the_section(section) -> None:
    """The defect: without the generated files, with Moss's fixed 10 and no minimum size, every pair is flagged."""
    subs, results = section
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(similarity, "common_limit", lambda students: max(10, students // 10))
        old = similar_pairs(results, subs, generated=False, min_shared=0)
    assert len(old.pairs) == 10 and all(pair.score > 0.99 for pair in old.pairs)


@needs_ros2pkg
def test_the_generated_files_alone_leave_out_the_false_pairs(section) -> None:
    """Whatever the class size: with a common-code limit no section reaches, the templates do it alone."""
    subs, results = section
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(similarity, "common_limit", lambda students: 10**6)
        comparison = similar_pairs(results, subs)
    assert _pairs(comparison) == [("ann", "ben"), ("cal", "dan")]


def test_the_common_limit_alone_leaves_out_the_false_pairs(section) -> None:
    """The fallback without ros2pkg: what 3 of a section of five share is the section's, not a pair's."""
    subs, results = section
    comparison = similar_pairs(results, subs, generated=False)
    assert _pairs(comparison) == [("ann", "ben"), ("cal", "dan")]


def test_the_common_limit_scales_with_the_section() -> None:
    assert [common_limit(n) for n in (2, 5, 8, 9, 15, 30, 100, 109, 300)] == [2, 2, 2, 3, 5, 10, 10, 10, 30]


@needs_ros2pkg
def test_every_generated_file_is_boilerplate_whatever_the_names(section) -> None:
    """Each file ``ros2 pkg create`` wrote for eve (own package name, maintainer, two dependencies) but the
    sample node she added to is left with no token of its own; so is a ``--build-type ament_cmake`` package."""
    subs, _results = section
    boilerplate = similarity._boilerplate((), True)
    package = next((subs / "eve" / "src").iterdir())
    files = {path.relative_to(package).as_posix(): path.read_text() for path in package.rglob("*") if path.is_file()}
    assert {"setup.py", "setup.cfg", "package.xml", "test/test_flake8.py", "test/test_copyright.py",
            "test/test_pep257.py", f"eve_pkg/{NODE}.py"} <= set(files)
    left = {}
    for rel, text in files.items():
        fingerprint = similarity._fingerprint(rel, text)
        if fingerprint is not None and similarity._wanted(rel, len(text)):
            similarity._strip(fingerprint, boilerplate.hashes)
            left[rel] = int(fingerprint.token_coverage)
    assert {rel for rel, tokens in left.items() if tokens} == {f"eve_pkg/{NODE}.py"}, left
    # the same for an ament_cmake package with a node and a library
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [ROS2PKG, os.environ.get("PYTHONPATH", "")])))
    script = _CREATE.replace("'ament_python', '--node-name', 'sample_python_node'",
                             "'ament_cmake', '--node-name', 'talker_node', '--library-name', 'talk_lib'")
    destination = subs.parent / "cmake"
    run = subprocess.run([sys.executable, "-c", script, json.dumps([(str(destination), "zed_cpp", "zed", ["rclcpp"])])],
                         env=env, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    files = {path.relative_to(destination).as_posix(): path.read_text()
             for path in sorted(destination.rglob("*")) if path.is_file()}
    # `namespace zed_cpp` keeps its name in copydetect's tokens: those templates are rendered per package too
    assert similarity._package_names(files) == {"zed_cpp"}
    drop = boilerplate.hashes | similarity._package_kgrams("zed_cpp")
    compared = 0
    for rel, text in files.items():
        fingerprint = similarity._fingerprint(rel, text)
        if fingerprint is not None and similarity._wanted(rel, 0):
            compared += 1
            similarity._strip(fingerprint, drop)
            assert not fingerprint.hashes, rel
    assert compared >= 5  # CMakeLists.txt, package.xml, the node, the library, its header


def test_a_pair_sharing_only_a_fragment_is_not_flagged() -> None:
    """Two students whose only code of their own is the same launch line in setup.py: 100 % alike, ~30 tokens."""
    line = "        (os.path.join('share', package_name, 'launch'), glob('launch/*.launch.py')),\n"
    setup = ("import os\nfrom glob import glob\nfrom setuptools import setup\n\npackage_name = 'p'\n\n"
             "setup(\n    name=package_name,\n    data_files=[\n" + line + "    ],\n)\n")
    others = {f"s{i}": {"setup.py": f"from setuptools import setup\n\nsetup(name='p{i}', version='{i}.0')\n"}
              for i in range(3)}
    sources = {"amy": {"setup.py": setup}, "bob": {"setup.py": setup.replace("'p'", "'q'")}, **others}
    flagged, _files, _given = compare_sources(LESSON, sources, [], min_shared=0)
    assert [(p.first, p.second) for p in flagged] == [("amy", "bob")] and flagged[0].shared_tokens < MIN_SHARED_TOKENS
    assert compare_sources(LESSON, sources, [])[0] == []


# --- The report remembers its submissions ---------------------------------------------------------------------


def _outdir(root: Path, results: list[LessonResult]) -> Path:
    out = root / "out"
    out.mkdir()
    (out / "results.jsonl").write_text("".join(json.dumps(r.to_record()) + "\n" for r in results))
    return out


def _section_text(out: Path) -> str:
    text = write_report(out).read_text(encoding="utf-8")
    return text[text.index('id="similar"'):]


def test_report_reads_the_submissions_the_run_recorded(section, tmp_path: Path) -> None:
    subs, results = section
    out = _outdir(tmp_path, results)
    (out / "run.json").write_text(json.dumps({"submissions": str(subs.resolve()), "lesson": LESSON}))
    text = _section_text(out)
    assert "ann / ben" in text and "cal / dan" in text and "ann / cal" not in text
    assert f"at least {MIN_SHARED_TOKENS} tokens" in text and "shared beyond boilerplate" in text


def test_report_says_why_without_a_recorded_folder(section, tmp_path: Path) -> None:
    _subs, results = section
    out = _outdir(tmp_path, results)
    assert "the run did not record its submissions folder" in _section_text(out)
    (out / "run.json").write_text(json.dumps({"lesson": LESSON}))  # an older runner: no submissions key
    assert "the run did not record its submissions folder" in _section_text(out)
    (out / "run.json").write_text("{truncated")
    assert "the run did not record its submissions folder" in _section_text(out)


def test_report_says_when_the_recorded_folder_is_gone(section, tmp_path: Path) -> None:
    _subs, results = section
    out = _outdir(tmp_path, results)
    gone = tmp_path / "moved-away"
    (out / "run.json").write_text(json.dumps({"submissions": str(gone)}))
    text = _section_text(out)
    assert f"the submissions folder {gone} recorded by the run is gone" in text and "ann / ben" not in text


def test_the_comparison_is_the_same_in_every_process() -> None:
    """copydetect hashes k-grams with ``hash()``, salted per process: two reports of one class could flag other
    pairs. The fingerprints (what winnowing keeps) must not depend on PYTHONHASHSEED."""
    code = ("import math\n\n\ndef heading(x, y):\n    total = 0\n    for i in range(10):\n        total += math.atan2(y, x) * i\n"
            "    return total / 10\n\n\nclass Odometry:\n    def __init__(self):\n        self.pose = [0.0, 0.0]\n")
    probe = ("import sys; from ros2course.report import similarity as s; f = s._fingerprint('a.py', sys.stdin.read()); "
             "print(sorted(int(h) for h in f.hashes)[:20], sorted(s._kgrams('a.py', 'x = 1\\n' * 40))[:5])")
    seen = {subprocess.run([sys.executable, "-c", probe], input=code, capture_output=True, text=True, check=True,
                           env={**os.environ, "PYTHONHASHSEED": seed}).stdout for seed in ("1", "2", "3")}
    assert len(seen) == 1, seen
