"""The topic, service and parameter graders are deterministic: the same correct submission gets the same
verdicts every time (issue 3).

For each lesson below the reference is
built once into a temporary workspace (later grades reuse the build: colcon
is skipped when the sources are unchanged), then graded twice (:data:`RUNS`). Score and
every check's verdict and points must not vary, although the grader makes up
new quotes (subscriber) and new points (stand-in server) each time and the
reference server answers with random points, and the parameters grader changes
parameters at runtime. ``inspect-topics`` and ``inspect-params`` run the reference
``ros2`` CLI script against mystery nodes with new random values (topic, id, quote,
publisher count, initial parameter) each time: one score every time. Under load a rate could drift,
so a failure lists every run that differed and how.
"""

from __future__ import annotations

import pytest

from ros2course.grade.engine import grade_lesson
from ros2course.grade.results import Status
from ros2course.dev.validate import reference_workspace
from ros2course.lesson.catalog import load_catalog

#: Gradings per lesson. 2 in the suite (CI time: 4 runs of 5 lessons took 6 min of test time, 3 runs 5.0 min in the
#: run of 2026-11-28, and the suite is over its 45-min budget; each reference is graded twice more by
#: test_validate, by check and by grade, whose verdicts must agree too); 20 at two at once is the goal, measured with ``python benchmarks/grader_strength.py LESSON --repeat 20 --load 2`` and recorded with each
#: lesson (``steadiness.json``, shown in docs/grader-strength.md). tests/test_repeat.py runs a short one at load 2.
RUNS = 2


def verdicts(result) -> list[tuple[str, bool, float]]:
    """(check id, passed, points) per check, in order."""
    return [(c.id, c.passed, c.points) for c in result.checks]


@pytest.mark.ros
@pytest.mark.usefixtures("cpu_exclusive")  # no C++ compile on the other core meanwhile (conftest)
@pytest.mark.timeout(1200)
# inspect-services: tests/test_repeat.py grades its reference three times, two at once (a harder test of the
# same thing, so it is not graded here again)
@pytest.mark.parametrize("lesson_id", ["publisher-subscriber", "service-server-client", "parameters",
                                       "inspect-topics", "inspect-params"])
def test_reference_grades_identically(lesson_id, tmp_path):
    lesson = load_catalog().get(lesson_id)
    workspace = reference_workspace(lesson, tmp_path / "ws")
    first = grade_lesson(lesson, workspace, log_dir=tmp_path / "log0")
    assert first.status == Status.PASSED, [(c.id, c.observed) for c in first.checks if not c.passed] or first.message
    assert first.build.get("ok") is True
    expected = verdicts(first)
    differences = []
    for run in range(1, RUNS):
        result = grade_lesson(lesson, workspace, log_dir=tmp_path / f"log{run}")
        assert result.build.get("cached") is True, "the build is reused after the first grade"
        if result.score != first.score or verdicts(result) != expected:
            differences.append(f"run {run}: {result.status} {result.score}/{result.max_score}; "
                               + "; ".join(f"{c.id}: {c.observed}" for c in result.checks if not c.passed))
    assert not differences, "\n".join(differences)
