"""A second course beside the tutorial (issue 18): tests/data/lab_course, made only with
``ros2course dev new-lesson``, validates, grades a learner's workspace and a class of two.

Real ROS nodes: the lesson's grader starts the learner's node and waits for it in the graph.
"""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pytest

from ros2course.grade.engine import load_grader
from ros2course.lesson import bundled_course

LAB_COURSE = Path(__file__).resolve().parent / "data" / "lab_course"
PACKAGE = "hello_node_pkg"

pytestmark = pytest.mark.ros


def test_the_scaffolded_course_validates(cli, tmp_path: Path) -> None:
    # --jobs 2: the starter and the wrong solution are graded in child processes, which must grade
    # this course's lesson (the bundled course has no hello-node), not the bundled one
    proc = cli("dev", "validate", "--course", str(LAB_COURSE), "--json", "--jobs", "2", cwd=tmp_path,
               env={"ROS2COURSE_CONTENT": ""})
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    outcomes = {o["case"]: o for o in json.loads(proc.stdout)}
    assert set(outcomes) == {"reference", "starter", "never-registered"}
    assert all(o["ok"] for o in outcomes.values()), outcomes
    assert outcomes["reference"]["result"]["score"] == 5


def test_a_class_of_two_is_batch_graded_on_it(cli, tmp_path: Path) -> None:
    submissions = tmp_path / "submissions"
    right = submissions / "ada" / "src" / PACKAGE
    shutil.copytree(LAB_COURSE / "solutions" / "src" / PACKAGE, right)
    wrong = submissions / "bob" / "src" / PACKAGE
    shutil.copytree(LAB_COURSE / "chapters" / "10-hello-node" / "starter" / "src" / PACKAGE, wrong)
    out = tmp_path / "out"
    proc = cli("grade", str(submissions), "--lesson", "hello-node", "--out", str(out), "--course", str(LAB_COURSE),
               "--jobs", "2", cwd=tmp_path, env={"ROS2COURSE_CONTENT": ""}, timeout=600)
    assert proc.returncode in (0, 1), proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = {row["student"]: row for row in csv.DictReader((out / "gradebook.csv").open())}
    assert set(rows) == {"ada", "bob"}
    records = {json.loads(line)["student"]: json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()}
    assert records["ada"]["score"] == records["ada"]["max_score"] == 5
    lost = {c["id"] for c in records["bob"]["checks"] if not c["passed"]}
    assert "executable" in lost and records["bob"]["score"] < 5


def test_its_graders_and_the_tutorial_s_live_side_by_side() -> None:
    lab = load_grader("hello_node", LAB_COURSE)
    tutorial = load_grader("print_forever_node", bundled_course())
    assert lab.__name__.split(".")[0] != tutorial.__name__.split(".")[0]
    assert {c.id for c in lab.CHECKS} == {"build", "executable", "node_name"}
