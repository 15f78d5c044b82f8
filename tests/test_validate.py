"""The course checks itself: every lesson's reference gets full marks, its starter does not,
and every wrong solution in tests/fixtures loses the points of the check that names its bug;
and ``ros2course grade`` (as root here: full isolation) gives the reference and one wrong
solution of each lesson the verdicts ``check`` gave them (``dev validate --batch``, issue 25)."""

from __future__ import annotations

import json

import pytest

from ros2course.lesson.catalog import load_catalog


@pytest.mark.ros
@pytest.mark.timeout(1500)
@pytest.mark.parametrize("lesson_id", load_catalog().ids())
def test_dev_validate(lesson_id, cli):
    # --jobs 3: wrong solutions three at once (most of a case is waiting: a goal's feedback, a deadline, a
    # discovery), references alone. Two validations at once as CI's two workers run them (gazebo-custom-nodes
    # beside actions-client): 207 s with --jobs 3 against 253 s with --jobs 2, the same verdicts and notes in
    # every case; the fresh-clone CI of --jobs 2 took 48.0 min, over its 45-min budget.
    # --until-settled: a wrong solution is graded until the checks its fixture names are judged, the starter
    # until its first lost point (the rest cannot change their verdicts); references whole. --batch grades the
    # reference beside the one sampled wrong solution (dev.parity.validate_with_batch: inspect-params 183 -> 154 s)
    proc = cli("dev", "validate", lesson_id, "--json", "--batch", "--sample", "1", "--jobs", "3", "--until-settled",
               timeout=1200)
    assert "Traceback" not in proc.stderr, proc.stderr
    # an error before the JSON (a one-line CourseError, a signal) must say itself in the failure
    assert proc.stdout.strip(), f"no JSON; exit status {proc.returncode}; stderr:\n{proc.stderr[-4000:]}"
    outcomes = json.loads(proc.stdout)
    cases = {o["case"] for o in outcomes}
    assert {"reference", "starter", "reference (grade)"} <= cases
    batch = [o for o in outcomes if o["case"].endswith(" (grade)")]
    assert len(batch) == 2, batch
    wrong = [o for o in outcomes if o["case"] not in ("reference", "starter") and o not in batch]
    assert wrong, f"{lesson_id} has no wrong-solution fixtures"
    # each failed check's observed text too: a flaky check found by CI is diagnosed from this message
    bad = [f"{o['case']}: expected {o['expected']}, got {o['got']}" + "".join(
        f"\n    {c['id']}: {c['observed'][:400]}" for c in ((o.get("result") or {}).get("checks") or [])
        if not c["passed"] or _lost_by_check(o, c["id"])) for o in outcomes if not o["ok"]]
    assert not bad, "\n".join(bad)
    assert proc.returncode == 0


def _lost_by_check(outcome: dict, check_id: str) -> bool:
    """Whether a ``(grade)`` case's ``expected`` (check's verdict: "as check: ... failed: a, b") lists ``check_id``
    as failed: a check grade passed and check failed shows what grade observed (CI of stop 72 did not)."""
    failed = outcome["expected"].rpartition("failed: ")[2].split(";")[0]
    return outcome["case"].endswith(" (grade)") and check_id in [c.strip() for c in failed.split(",")]


def test_a_fixture_that_does_not_build_fails_only_for_the_build() -> None:
    """A not-gradable result (no checks ran) proves a fixture's bug only when the fixture names the build."""
    from ros2course.grade.results import CheckResult, LessonResult
    from ros2course.dev.validate import judge_fixture

    broken = LessonResult("l", 0.0, 10.0, "not gradable", [], "colcon build failed")
    assert judge_fixture(["build"], broken)[0]
    ok, expected = judge_fixture(["rate"], broken)
    assert not ok and "never judged" in expected and "rate" in expected
    assert not judge_fixture(["build", "rate"], broken)[0]
    graded = LessonResult("l", 8.0, 10.0, "failed", [
        CheckResult("build", "b", 1, 1, True, "", "", ""),
        CheckResult("rate", "r", 0, 2, False, "", "", ""),
        CheckResult("log", "g", 7, 7, True, "", "", "")])
    assert judge_fixture(["rate"], graded)[0]
    assert not judge_fixture(["rate", "log"], graded)[0]
    assert "unknown check ids: nope" in judge_fixture(["nope"], graded)[1]
    # the grader failing half-way proves nothing about the fixture, even with its named check lost on the way
    crashed = LessonResult("l", 1.0, 10.0, "grader error", graded.checks, "FileNotFoundError: crypto/my_key")
    ok, expected = judge_fixture(["rate"], crashed)
    assert not ok and "the grader failed: FileNotFoundError" in expected



def test_a_wrong_case_shows_what_its_failed_checks_observed() -> None:
    """A reference that lost a check once (a flaky check) leaves in the CI log what the check saw."""
    import io  # noqa: PLC0415

    from rich.console import Console  # noqa: PLC0415

    from ros2course.grade.results import CheckResult, LessonResult  # noqa: PLC0415
    from ros2course.dev.validate import Outcome, render_outcomes  # noqa: PLC0415

    result = LessonResult("lifecycle-node", 21.0, 25.0, "failed", [
        CheckResult("activate", "a", 2, 2, True, "activated", "", ""),
        CheckResult("active_messages", "m", 0, 2, False, "nothing sent on /heartbeat in 2.1 s", "", "")])
    out = io.StringIO()
    render_outcomes([Outcome("lifecycle-node", "reference", False, "full marks", "failed 21/25", 8.0, result),
                     Outcome("lifecycle-node", "starter", True, "not full marks", "failed 3/25", 1.0, result)],
                    Console(file=out, width=200))
    shown = out.getvalue()
    assert "lifecycle-node reference: active_messages: nothing sent on /heartbeat in 2.1 s" in shown
    assert "starter: active_messages" not in shown and "activated" not in shown


def test_a_fixture_can_require_the_words_its_feedback_must_contain() -> None:
    """``says:`` in a fixture: losing the right check is not enough, the learner must be told what they did."""
    from ros2course.grade.results import CheckResult, LessonResult
    from ros2course.dev.validate import judge_fixture

    graded = LessonResult("l", 1.0, 3.0, "failed", [
        CheckResult("build", "b", 1, 1, True, "", "", ""),
        CheckResult("order", "o", 0, 2, False, "the calls ran One after the other", "", "create tasks first")])
    assert judge_fixture(["order"], graded, {"order": ["one after the other", "tasks"]})[0]
    ok, expected = judge_fixture(["order"], graded, {"order": ["rolls ran out"]})
    assert not ok and "missing: order says 'rolls ran out'" in expected


def test_a_case_with_the_references_sources_is_graded_in_the_references_build(tmp_path, monkeypatch) -> None:
    """``dev validate`` grades a wrong solution that changes no package in the reference's built
    workspace (nothing else of the reference's survives), and one that changes a package from scratch."""
    import shutil
    from pathlib import Path

    from ros2course.dev import validate

    pristine = tmp_path / "pristine"
    (pristine / "src" / "pkg").mkdir(parents=True)
    (pristine / "src" / "pkg" / "package.xml").write_text(
        '<?xml version="1.0"?><package format="3"><name>pkg</name><version>0.0.0</version>'
        '<description>d</description><maintainer email="ta@example.com">ta</maintainer><license>MIT</license></package>')
    (pristine / "cli").mkdir()
    (pristine / "cli" / "run.sh").write_text("ros2 topic list\n")
    built = tmp_path / "built"
    shutil.copytree(pristine, built)  # copies keep mtimes, as reference_workspace's do
    for folder in ("build/pkg", "install/pkg"):
        (built / folder).mkdir(parents=True)
    (built / "dump.yaml").write_text("written by the reference's grading\n")
    reference_src = validate._src_fingerprints(built)
    seen: list[set[str]] = []
    monkeypatch.setattr(validate, "grade_lesson", lambda lesson, root, underlays=(), stop_when=None: seen.append(
        {str(p.relative_to(root)) for p in Path(root).rglob("*")}) or "graded")

    def script_edited(root: Path) -> None:
        shutil.copytree(pristine, root, dirs_exist_ok=True)
        (root / "cli" / "run.sh").write_text("ros2 topic lst\n")

    def package_edited(root: Path) -> None:
        script_edited(root)
        (root / "src" / "pkg" / "setup.cfg").write_text("[develop]\n")

    lesson = load_catalog().get("inspect-topics")
    case = validate.Case(lesson, "script_edited", script_edited, (), lambda r: (True, ""))
    result, _ = validate.grade_in_built(lesson, case, built, reference_src)
    assert result == "graded"
    assert {"build/pkg", "install/pkg", "cli/run.sh", "src/pkg/package.xml"} <= seen[0]
    assert "dump.yaml" not in seen[0]
    assert (built / "cli" / "run.sh").read_text() == "ros2 topic lst\n"
    other = validate.Case(lesson, "package_edited", package_edited, (), lambda r: (True, ""))
    assert validate.grade_in_built(lesson, other, built, reference_src) is None
    assert len(seen) == 1
    assert validate.grade_in_built(lesson, case, built, None) is None, "an unparsable reference never matches"

    def built_by_its_commands(root: Path) -> None:  # workspace-setup's reference commands run colcon themselves
        script_edited(root)
        (root / "install").mkdir()

    own = validate.Case(lesson, "own_build", built_by_its_commands, (), lambda r: (True, ""))
    assert validate.grade_in_built(lesson, own, built, reference_src) is None
    assert len(seen) == 1


def test_a_fixture_case_judges_its_skips_and_notes_what_else_it_lost(monkeypatch) -> None:
    """``dev validate``'s fixture cases pass the fixture's ``skips`` to the judge, and note the checks
    it names nowhere."""
    import io  # noqa: PLC0415

    from rich.console import Console  # noqa: PLC0415

    from ros2course.dev import validate  # noqa: PLC0415
    from ros2course.grade.results import CheckResult, LessonResult  # noqa: PLC0415

    fixture = validate.Fixture.model_validate({"description": "d", "fails": ["a"], "skips": ["b"],
                                               "edits": [{"delete": "src/nothing"}]})
    fixture.name = "wrong_a"
    monkeypatch.setattr(validate, "load_fixtures", lambda lesson_id: [fixture])
    reference, starter, case = validate.lesson_cases(load_catalog().get("print-forever-node"), None)
    assert reference.note is None and starter.note is None
    result = LessonResult("print-forever-node", 1.0, 10.0, "failed", [
        CheckResult("a", "A", 0, 4, False, "wrong", "", ""),
        CheckResult("b", "B", 0, 3, False, "not checked: 'A' failed", "", "", skipped=True),
        CheckResult("c", "C", 1, 3, False, "half", "", "")])
    ok, expected = case.judge(result)
    assert ok and "not checked: b" in expected
    assert case.note(result) == "also lost: c"
    out = io.StringIO()
    validate.render_outcomes([validate.Outcome("print-forever-node", case.name, ok, expected, "failed 1/10", 1.0,
                                               result, note=case.note(result))], Console(file=out, width=300))
    assert "failed 1/10; also lost: c" in out.getvalue()


def test_every_lesson_has_a_reference_workspace_with_and_without_tests(tmp_path) -> None:
    """reference_workspace copies each lesson's packages and folders (a lesson may have no package, only folders);
    shared builds (with_tests=False) leave out each package's own test/ folder and nothing else."""
    from ros2course.builder.reference import reference_workspace

    for lesson in load_catalog().lessons:
        whole = reference_workspace(lesson, tmp_path / lesson.id / "whole")
        bare = reference_workspace(lesson, tmp_path / lesson.id / "bare", with_tests=False)
        files = {p.relative_to(whole) for p in whole.rglob("*") if p.is_file()}
        kept = {p.relative_to(bare) for p in bare.rglob("*") if p.is_file()}
        assert kept <= files, lesson.id
        assert {p for p in files - kept if not (len(p.parts) > 2 and p.parts[0] == "src" and p.parts[2] == "test")} \
            == set(), (lesson.id, sorted(files - kept)[:5])
        assert not any(len(p.parts) > 2 and p.parts[0] == "src" and p.parts[2] == "test" for p in kept), lesson.id
    assert (tmp_path / "testing-your-nodes" / "whole" / "src" / "python_package_with_a_node" / "test").is_dir()
