"""``ros2course dev validate``: the course checks itself (rustlings' ``dev check``).

For every lesson:

* its reference solution (``solutions/``) must get full marks;
* its starter files must not;
* every wrong solution kept in ``tests/fixtures/<lesson-id>/*.yaml`` must
  lose the points of the checks it names (and a fixture marked
  ``expect: full_marks``, e.g. the seed's own Humble-style listing, must pass).

A wrong solution is the reference plus a few edits, so the fixture file
shows exactly the bug and nothing else::

    description: the timer period is 1.0 s instead of 0.5 s
    fails: [rate]
    edits:
      - file: src/python_package_with_a_node/python_package_with_a_node/print_forever_node.py
        replace: "timer_period: float = 0.5"
        with: "timer_period: float = 1.0"

``fails:`` names only checks that were judged and lost points. A check that
was not judged because a check it needs failed (shown as "not checked") goes
under ``skips:``, and must be not checked::

    description: the node is named print_node instead of print_forever_node
    fails: [node_name]
    skips: [rate]

Any other check the fixture lost, or that was not checked, is reported on
its line of ``dev validate`` ("also lost: ..."), not a failure.

``--until-settled`` (the test suite's way) stops grading a case at the grader's next step once its
verdict can no longer change (:class:`~ros2course.grade.checklist.StopWhen`): a wrong solution once every
check its fixture names (``fails``, ``skips``, ``says`` and its diagnoses' checks) is judged, which
leaves a third of a lesson's checks on average (a wrong solution waiting for a topic that never comes
is most of the time); a starter at its first lost point. Their other checks then show "not checked"
(:data:`~ros2course.grade.checklist.STOPPED_SETTLED`) and no "also lost" note is made. References and
``expect: full_marks`` fixtures are graded whole.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import queue
import shutil
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator
from rich.console import Console
from rich.markup import escape
from rich.table import Table
from ros2course.dev import first_line
from ros2course.builder.reference import (
    ReferenceBuild,
    lesson_dependencies,
    reference_workspace,
    shared_reference_build,
)
from ros2course.builder.sources import scan_package
from ros2course.errors import CourseError, LessonFormatError, ValidationFailed
from ros2course.dev.child import grade_in_child
from ros2course.dev.coverage import lesson_coverage
from ros2course.grade.engine import grade_lesson, load_grader
from ros2course.dev.mutants import describe_score, score_text, triage_problems, unjudged
from ros2course.grade.checklist import StopWhen
from ros2course.grade.results import LessonResult, Status
from ros2course.dev.strength import steadiness_text
from ros2course.lesson.catalog import Lesson, content_root, load_catalog
from ros2course.lesson.schema import format_validation_error
from ros2course.lesson.courses import course_fixtures
from ros2course.lesson.starter import copy_starter
from ros2course.ros import env as env_mod
from ros2course.ros.manifests import find_packages


class Edit(BaseModel):
    """One change to the reference workspace: replace text once, write a file, or delete a path."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True)

    file: str | None = None
    replace: str | None = None
    with_: str | None = Field(default=None, alias="with")
    content: str | None = None
    delete: str | None = None

    @model_validator(mode="after")
    def _one_kind(self) -> Edit:
        kinds = [self.replace is not None, self.content is not None, self.delete is not None]
        if sum(kinds) != 1:
            raise ValueError("an edit has exactly one of 'replace' (with 'with'), 'content' or 'delete'")
        if (self.replace is not None or self.content is not None) and not self.file:
            raise ValueError("'replace' and 'content' edits need 'file'")
        if self.replace is not None and self.with_ is None:
            raise ValueError("'replace' needs 'with'")
        return self


class ExpectedDiagnosis(BaseModel):
    """A finding a wrong solution's result must carry (:mod:`ros2course.run.diagnose`, issue 19).

    Attributes:
        kind: the finding's kind (:data:`ros2course.run.diagnose.KINDS`: ``process``, ``near_name``, ``other_type``,
            ``qos``, ``no_peer``, ``duplicate_node``, ``silent``).
        mentions: words its message or detail must contain, case-insensitively (e.g. the names involved).
        check: the check id whose diagnosis holds it; "" for any failed check.
    """

    model_config = ConfigDict(extra="forbid")

    kind: Literal["process", "near_name", "other_type", "qos", "no_peer", "duplicate_node", "silent"]
    mentions: list[str] = Field(default_factory=list)
    check: str = ""


class Fixture(BaseModel):
    """A wrong (or alternative right) solution of one lesson."""

    model_config = ConfigDict(extra="forbid")

    description: str
    expect: Literal["fail", "full_marks"] = "fail"
    #: checks that must be judged and lose points (the bug's own checks).
    fails: list[str] = Field(default_factory=list)
    #: checks that must be "not checked": not judged because a check they need failed.
    skips: list[str] = Field(default_factory=list)
    edits: list[Edit] = Field(default_factory=list)
    #: shell commands run in the workspace after the edits (default: the lesson's reference commands).
    commands: list[str] | None = None
    #: check id -> words its feedback (observed text or hint) must contain, case-insensitively: a wrong
    #: solution must lose the right check *and* be told what it did (issue 24).
    says: dict[str, list[str]] = Field(default_factory=dict)
    #: findings the engine's diagnosis of the failed checks must hold (the bug's cause, named).
    diagnosis: list[ExpectedDiagnosis] = Field(default_factory=list)

    name: str = Field(default="", exclude=True)

    @model_validator(mode="after")
    def _fails_named(self) -> Fixture:
        if self.expect == "fail" and not self.fails:
            raise ValueError("a failing fixture names the check(s) its bug must fail in 'fails'")
        if self.expect == "full_marks" and self.skips:
            raise ValueError("a fixture that expects full marks cannot name checks in 'skips' (every check is judged)")
        both = [c for c in self.skips if c in self.fails]
        if both:
            raise ValueError(f"{', '.join(both)} cannot be in both 'fails' (judged and lost) and 'skips' "
                             "(not checked): keep each check in one list")
        return self

    def judged_by(self) -> tuple[str, ...]:
        """The checks whose verdicts decide this fixture (``fails``, ``skips``, ``says``' and diagnoses'
        checks), in that order; () when grading must run to its end: a fixture expecting full marks,
        or one expecting a diagnosis of any failed check (``check: ""``)."""
        if self.expect != "fail" or any(not d.check for d in self.diagnosis):
            return ()
        return tuple(dict.fromkeys([*self.fails, *self.skips, *self.says, *(d.check for d in self.diagnosis)]))


def fixtures_dir(lesson_id: str) -> Path:
    """Where the lesson's fixture YAML files live (``<course fixtures>/<lesson-id>``, see ``course.yaml``)."""
    return course_fixtures(content_root()) / lesson_id


def load_fixtures(lesson_id: str) -> list[Fixture]:
    """Every ``tests/fixtures/<lesson>/*.yaml``, validated.

    Raises:
        LessonFormatError: a fixture file is malformed (file and field named).
    """
    out = []
    for path in sorted(fixtures_dir(lesson_id).glob("*.yaml")):
        try:
            data = yaml.safe_load(path.read_text(encoding="utf-8"))
            fixture = Fixture.model_validate(data)
        except yaml.YAMLError as exc:
            raise LessonFormatError(f"{path}: not readable as YAML: {exc}", "fix the fixture's YAML") from exc
        except ValidationError as exc:
            raise LessonFormatError(format_validation_error(path, exc), "see course/dev/validate.py (Fixture)") from exc
        fixture.name = path.stem
        out.append(fixture)
    return out


def apply_edits(workspace_root: Path, edits: list[Edit]) -> None:
    """Apply a fixture's edits to a workspace copy.

    Raises:
        LessonFormatError: a ``replace`` text does not occur exactly once.
    """
    for edit in edits:
        if edit.delete is not None:
            target = workspace_root / edit.delete
            if target.is_dir():
                shutil.rmtree(target)
            else:
                target.unlink(missing_ok=True)
            continue
        target = workspace_root / edit.file
        if edit.content is not None:
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(edit.content, encoding="utf-8")
            continue
        text = target.read_text(encoding="utf-8")
        count = text.count(edit.replace)
        if count != 1:
            raise LessonFormatError(f"{edit.file}: the text to replace occurs {count} times (must be once): "
                                    f"{edit.replace!r}", "make 'replace' longer so it is unique")
        target.write_text(text.replace(edit.replace, edit.with_), encoding="utf-8")


def build_underlay(lesson: Lesson) -> ReferenceBuild | None:
    """The lesson's dependencies, built as an underlay for every validation case (shared between
    lessons and runs while their files do not change: :func:`~ros2course.builder.reference.shared_reference_build`).

    The standard ROS overlay mechanism: each case's workspace is built and
    sourced on top of this one, so an interface package is built once
    instead of once per case. Returns None when there is nothing to build.

    Raises:
        ValidationFailed: the reference dependencies do not build.
    """
    deps = lesson_dependencies(lesson)
    if not deps:
        return None
    try:
        return shared_reference_build(lesson, deps, "underlay-build.log")
    except CourseError as exc:
        raise ValidationFailed(exc.message, exc.hint) from exc


def run_commands(workspace_root: Path, commands: list[str]) -> None:
    """Run shell commands in the workspace as a learner would (errors are the grader's to see)."""
    env = env_mod.activate()
    for command in commands:
        subprocess.run(["bash", "-c", command], cwd=workspace_root, env=env, stdin=subprocess.DEVNULL,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=600, check=False)


@dataclasses.dataclass
class Outcome:
    """One validation case: reference, starter or a fixture of one lesson."""

    lesson: str
    case: str
    ok: bool
    expected: str
    got: str
    seconds: float = 0.0
    result: LessonResult | None = None
    #: ``path:line: message`` lines of the case (the ``contract.yaml`` case: :func:`contract_outcome`).
    problems: list[str] = dataclasses.field(default_factory=list)
    #: what else the case showed, not a failure: a fixture's checks lost beyond those it names
    #: (:func:`fixture_note`, e.g. "also lost: rate, counts_from_zero"); "" when nothing.
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        found = {"lesson": self.lesson, "case": self.case, "ok": self.ok, "expected": self.expected,
                 "got": self.got, "seconds": round(self.seconds, 2),
                 "result": self.result.to_json() if self.result else None}
        if self.problems:
            found["problems"] = list(self.problems)
        if self.note:
            found["note"] = self.note
        return found

    def line(self) -> str:
        """The case's progress line (after its mark): what it got, its time and its note."""
        return f"{self.case}: {self.got} ({self.seconds:.1f} s)" + (f"; {self.note}" if self.note else "")


#: The case name of a lesson's contract coverage (issue 37); no fixture is named so (a fixture's name has no dot).
CONTRACT_CASE = "contract.yaml"
#: What ``dev validate`` says of a lesson without a ``contract.yaml``: a warning, not a failure.
NO_CONTRACT = "no contract coverage"


def contract_outcome(lesson: Lesson) -> Outcome | None:
    """The ``contract.yaml`` case of ``lesson``: its requirements traced to checks, every problem a failure.

    None when the lesson has no ``contract.yaml`` (:data:`NO_CONTRACT`, a warning the caller prints).
    """
    begin = time.monotonic()
    row = lesson_coverage(lesson)
    expected = "every requirement traced to checks of the grader or marked not graded (issue 37)"
    if row.contract is None and not row.problems:
        return None
    if row.problems:
        return Outcome(lesson.id, CONTRACT_CASE, False, expected, f"{len(row.problems)} problem(s): {row.problems[0]}",
                       time.monotonic() - begin, problems=[str(p) for p in row.problems])
    assert row.contract is not None
    contract = row.contract
    return Outcome(lesson.id, CONTRACT_CASE, True, expected,
                   f"{len(contract.requirements)} requirements: {len(contract.mapped)} mapped, "
                   f"{len(contract.not_graded)} not graded", time.monotonic() - begin)


def _describe(result: LessonResult) -> str:
    cut = unjudged(result)
    failed = ", ".join(c for c in result.failed_checks() if c not in cut) or "none"
    text = f"{result.status} {result.score:g}/{result.max_score:g}; failed: {failed}"
    if cut:
        text += f"; {len(cut)} not judged (--until-settled)"
    if result.message and result.status != Status.PASSED:
        text += f"; {first_line(result.message, cap=1000)}"
    return text


#: ``grade(lesson, root, underlays)``: how a validation case is graded (in this process, or in a child).
Grade = Callable[[Lesson, Path, tuple[Path, ...]], LessonResult]


def grade_here(lesson: Lesson, root: Path, underlays: tuple[Path, ...], stop_when: StopWhen | None = None
               ) -> LessonResult:
    """Grade ``root`` in this process (:func:`~ros2course.grade.engine.grade_lesson`; ``stop_when``: its
    ``--until-settled`` stop, None for a whole grading)."""
    return grade_lesson(lesson, root, underlays=underlays, stop_when=stop_when)


def grade_case(lesson: Lesson, case: str, prepare, keep: bool = False,
               underlays: tuple[Path, ...] = (), grade: Grade = grade_here) -> tuple[LessonResult, float]:
    """Grade a throw-away workspace that ``prepare(root)`` fills; returns the result and seconds."""
    root = Path(tempfile.mkdtemp(prefix=f"ros2course-validate-{lesson.id}-{case}-"))
    begin = time.monotonic()
    try:
        prepare(root)
        result = grade(lesson, root, underlays)
        return result, time.monotonic() - begin
    finally:
        if not keep:
            shutil.rmtree(root, ignore_errors=True)


def validate_lesson(lesson: Lesson, jobs: int = 1, until_settled: bool = False) -> list[Outcome]:
    """Validate one lesson: reference, starter, fixtures (see module docstring).

    Args:
        jobs: wrong solutions graded at once (see :func:`_validate_lesson`).
        until_settled: grade each wrong solution and the starter only until their verdicts are settled
            (``--until-settled``).
    """
    underlay = build_underlay(lesson)
    try:
        return _validate_lesson(lesson, underlay.path if underlay is not None else None, jobs, until_settled)
    finally:
        if underlay is not None:
            underlay.discard()


@dataclasses.dataclass
class Case:
    """One validation case of a lesson: how to fill its workspace and how to judge its result.

    Attributes:
        lesson: the lesson.
        name: ``reference``, ``starter`` or a fixture's name.
        prepare: ``prepare(root)`` fills an empty folder with the case's workspace (and runs its commands).
        underlays: built workspaces sourced before building it (the lesson's dependencies).
        judge: ``judge(result)`` -> ``(ok, expected text)``.
        alone: the case expects full marks (the reference, a fixture with ``expect: full_marks``):
            with ``--jobs``, it is graded with nothing of the validation beside it, since a timing
            check must hold under a normal load, not beside gradings of its own making.
        note: ``note(result)`` -> what else the result showed, not a failure (:attr:`Outcome.note`); None: nothing.
        stop_when: with ``--until-settled``, when its grading may stop (a wrong solution: its named checks
            judged, :meth:`Fixture.judged_by`; the starter: its first lost point); None: graded whole.
    """

    lesson: Lesson
    name: str
    prepare: Callable[[Path], None]
    underlays: tuple[Path, ...]
    judge: Callable[[LessonResult], tuple[bool, str]]
    alone: bool = False
    note: Callable[[LessonResult], str] | None = None
    stop_when: StopWhen | None = None

    def grade_with(self, grade: Grade) -> Grade:
        """``grade`` with this case's ``stop_when`` (a whole grading when it has none)."""
        if not self.stop_when:
            return grade
        return lambda lesson, root, underlays: grade(lesson, root, underlays, stop_when=self.stop_when)


def lesson_cases(lesson: Lesson, underlay: Path | None, until_settled: bool = False) -> list[Case]:
    """The lesson's reference, starter and wrong solutions (``tests/fixtures/<lesson>``) as cases.

    Args:
        underlay: the lesson's dependencies built once (:func:`build_underlay`), or None.
        until_settled: each wrong solution and the starter are graded only until their verdict is settled
            (:attr:`Case.stop_when`; ``dev validate --until-settled``).

    Raises:
        LessonFormatError: a fixture file is malformed.
    """
    deps = lesson_dependencies(lesson) if underlay is not None else []
    own = list(lesson.packages)
    underlays = (underlay,) if underlay is not None else ()

    def reference(root: Path) -> None:
        reference_workspace(lesson, root, own if underlay is not None else None)
        run_commands(root, lesson.reference.commands)

    def starter(root: Path) -> None:
        (root / "src").mkdir(parents=True)
        copy_starter(lesson, root)

    def full_marks(result: LessonResult) -> tuple[bool, str]:
        return result.status == Status.PASSED, "full marks"

    def not_full(result: LessonResult) -> tuple[bool, str]:
        # a learner's first check runs on the starter: the grader must judge it, never fail on it
        # (cryptography's starter once ended in a FileNotFoundError and still counted as "not full marks")
        if result.status == Status.GRADER_ERROR:
            return False, f"not full marks, judged (but the grader failed: {first_line(result.message)})"
        return result.status != Status.PASSED and result.score < result.max_score, "not full marks"

    cases = [Case(lesson, "reference", reference, underlays, full_marks, alone=True),
             Case(lesson, "starter", starter, underlays, not_full,
                  stop_when=StopWhen(any_loss=True) if until_settled else None)]
    for fixture in load_fixtures(lesson.id):
        # a fixture that edits a dependency builds everything itself, without the underlay
        touched = {Path(e.file or e.delete or "").parts[1:2] for e in fixture.edits}
        uses_underlay = underlay is not None and not any(part and part[0] in _folders(lesson, deps) for part in touched)

        def wrong(root: Path, fixture: Fixture = fixture, uses_underlay: bool = uses_underlay) -> None:
            reference_workspace(lesson, root, own if uses_underlay else None)
            apply_edits(root, fixture.edits)
            run_commands(root, lesson.reference.commands if fixture.commands is None else fixture.commands)

        def judged(result: LessonResult, fixture: Fixture = fixture) -> tuple[bool, str]:
            if fixture.expect == "full_marks":
                return full_marks(result)
            return judge_fixture(fixture.fails, result, fixture.says, fixture.diagnosis, skips=fixture.skips)

        def noted(result: LessonResult, fixture: Fixture = fixture) -> str:
            return fixture_note(fixture.fails, fixture.skips, result)

        judged_by = frozenset(fixture.judged_by()) if until_settled else frozenset()
        cases.append(Case(lesson, fixture.name, wrong, underlays if uses_underlay else (), judged,
                          alone=fixture.expect == "full_marks",
                          note=noted if fixture.expect == "fail" and not judged_by else None,
                          stop_when=StopWhen(judged_by) if judged_by else None))
    return cases


#: What a case keeps of the workspace it reuses: colcon's output (absolute paths inside, so it cannot move).
_BUILT = ("build", "install")


def _src_fingerprints(root: Path) -> dict[str, str] | None:
    """``package folder -> content digest`` of a workspace's ``src/`` (what the build record compares);
    None when a ``package.xml`` there does not parse (such a case is always graded from scratch)."""
    try:
        found = find_packages(root / "src")
    except CourseError:
        return None
    return {str(path.relative_to(root)): scan_package(path, path).digest for path, _ in found.values()}


def grade_in_built(lesson: Lesson, case: Case, built: Path, reference_src: dict[str, str] | None,
                   grade: Grade = grade_here) -> tuple[LessonResult, float] | None:
    """Grade ``case`` in the workspace ``built`` (the reference, built), when its ``src/`` is the reference's.

    Most wrong solutions of the ``ros2`` CLI and script lessons change a script,
    not a package: their build would be the reference's, to the byte. Their
    workspace is made fresh in a scratch folder and moved into ``built`` over
    everything but ``build/`` and ``install/`` (nothing the reference's grading
    wrote survives), so the engine's build record (the sources' content, in the
    same folders) finds the packages built. A case whose
    ``src/`` differs in any file returns None, to be graded from scratch. ``built`` may
    also be an empty folder: the case is then built there, for the next case to reuse.
    """
    begin = time.monotonic()
    scratch = Path(tempfile.mkdtemp(prefix=f"ros2course-validate-{lesson.id}-{case.name}-"))
    try:
        case.prepare(scratch)
        if reference_src is None or _src_fingerprints(scratch) != reference_src:
            return None
        if any((scratch / name).exists() for name in _BUILT):
            return None  # the case's own commands built it (workspace-setup hands in its build): that build is graded
        for entry in list(built.iterdir()):
            if entry.name not in _BUILT:
                shutil.rmtree(entry) if entry.is_dir() and not entry.is_symlink() else entry.unlink()
        for entry in scratch.iterdir():
            shutil.move(str(entry), built / entry.name)
        return grade(lesson, built, case.underlays), time.monotonic() - begin
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _validate_lesson(lesson: Lesson, underlay: Path | None, jobs: int = 1,
                     until_settled: bool = False) -> list[Outcome]:
    """Grade every case; the reference's built workspace is reused by cases with the reference's ``src/``.

    With ``jobs`` > 1 the cases that expect full marks (:attr:`Case.alone`) are graded first,
    one at a time, in this process; then the others (the starter, the wrong solutions) ``jobs``
    at once, each in a child process (:func:`~ros2course.dev.child.grade_in_child`, as two
    learners' checks on one machine). A wrong solution hanging until its deadline is most of a
    lesson's validation time and needs no CPU: the others are graded meanwhile. Each of the
    ``jobs`` slots keeps a built copy of the reference (the first case it grades builds it).
    Outcomes keep the cases' order.
    """
    cases = lesson_cases(lesson, underlay, until_settled)
    scratch = Path(tempfile.mkdtemp(prefix=f"ros2course-validate-{lesson.id}-"))
    built = scratch / "built"
    built.mkdir()
    graded: dict[str, tuple[LessonResult, float]] = {}
    try:
        reference = cases[0]
        begin = time.monotonic()
        reference.prepare(built)
        # a lesson whose reference commands build the workspace themselves (workspace-setup) grades that
        # build: each of its cases keeps its own, so none reuses the reference's
        hands_in_build = any((built / name).exists() for name in _BUILT)
        reference_src = None if hands_in_build else _src_fingerprints(built)
        reference_src = reference_src or None  # no package: no build to spare, every case from scratch
        graded[reference.name] = (grade_lesson(lesson, built, underlays=reference.underlays),
                                  time.monotonic() - begin)

        def grade_one(case: Case, slot: Path, grade: Grade) -> tuple[LessonResult, float]:
            grade = case.grade_with(grade)
            found = None
            if case.underlays == reference.underlays:
                found = grade_in_built(lesson, case, slot, reference_src, grade)
            return found or grade_case(lesson, case.name, case.prepare, underlays=case.underlays, grade=grade)

        rest = [case for case in cases if case is not reference]
        parallel = [case for case in rest if not case.alone] if jobs > 1 else []
        for case in rest:
            if case not in parallel:
                graded[case.name] = grade_one(case, built, grade_here)
        if parallel:
            logs = scratch / "logs"
            slots: queue.SimpleQueue[Path] = queue.SimpleQueue()
            for index in range(min(jobs, len(parallel))):
                slot = built if index == 0 else scratch / f"built{index}"
                slot.mkdir(exist_ok=True)
                slots.put(slot)

            def in_child(case_lesson: Lesson, root: Path, underlays: tuple[Path, ...],
                         stop_when: StopWhen | None = None) -> LessonResult:
                return grade_in_child(case_lesson.id, root, underlays, Path(tempfile.mkdtemp(dir=logs)),
                                      stop_when=stop_when)

            def in_a_slot(case: Case) -> tuple[LessonResult, float]:
                slot = slots.get()
                try:
                    return grade_one(case, slot, in_child)
                finally:
                    slots.put(slot)

            logs.mkdir()
            with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
                for case, found in zip(parallel, pool.map(in_a_slot, parallel), strict=True):
                    graded[case.name] = found
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    outcomes = []
    for case in cases:
        result, seconds = graded[case.name]
        ok, expected = case.judge(result)
        outcomes.append(Outcome(lesson.id, case.name, ok, expected, _describe(result), seconds, result,
                                note=case.note(result) if case.note is not None else ""))
    return outcomes


#: The check a fixture names when its bug is that the workspace does not build (grading.grade_lesson).
BUILD_CHECK = "build"


def judge_fixture(fails: list[str], result: LessonResult, says: dict[str, list[str]] | None = None,
                  diagnosis: list[ExpectedDiagnosis] | None = None, *,
                  skips: list[str] | None = None) -> tuple[bool, str]:
    """Whether a wrong solution failed for its stated reason: ``(ok, expected text)``.

    It must lose the points of every check in ``fails`` (ids the grader
    declares), each of them judged: a check that was not judged because a
    check it needs failed ("not checked", :attr:`CheckResult.skipped`) proves
    nothing about itself, and belongs in ``skips``, whose every check must be
    not checked. A submission that is not gradable at all has no checks: that is
    its stated reason only when ``fails`` names the build (a fixture whose bug
    is a runtime behaviour must build, or it proves nothing about that check).
    ``says`` maps check ids to words their feedback must contain; each of
    ``diagnosis`` must be matched by a finding of that kind, mentioning every
    one of its words, on a failed check (the one it names, if any). Other checks
    lost are not judged here (:func:`fixture_note` reports them). A grading that
    ended in a grader error proves nothing, whatever checks it lost on the way.
    """
    skips = list(skips or [])
    expected = "loses the points of " + ", ".join(fails)
    if skips:
        expected += "; not checked: " + ", ".join(skips)
    if result.status == Status.GRADER_ERROR:  # the grader's own failure proves nothing about the fixture's bug
        return False, expected + f" (but the grader failed: {first_line(result.message) or '?'})"
    if not result.checks:
        if set(fails) == {BUILD_CHECK} and result.status == Status.NOT_GRADABLE and not skips:
            return True, expected
        runtime = [c for c in fails + skips if c != BUILD_CHECK]
        return False, expected + (f" (but it was {result.status} before any check ran, so {', '.join(runtime)} "
                                  "were never judged: the fixture must build)" if runtime else "")
    by_id = {c.id: c for c in result.checks}
    unknown = [c for c in fails + skips if c not in by_id]
    lost = [c for c in fails if c in by_id and not by_id[c].skipped and by_id[c].points < by_id[c].max_points]
    if unknown:
        expected += f" (unknown check ids: {', '.join(unknown)})"
    wrong_list = []
    for check_id in fails:
        check = by_id.get(check_id)
        if check is not None and check.skipped:
            wrong_list.append(f"{check_id} was not checked (a check it needs failed): list it under skips:")
    for check_id in skips:
        check = by_id.get(check_id)
        if check is not None and not check.skipped:
            wrong_list.append(f"{check_id} was judged, not skipped: "
                              + ("list it under fails:" if check.points < check.max_points
                                 else "it kept its points"))
    if wrong_list:
        expected += f" ({'; '.join(wrong_list)})"
    unsaid = []
    for check_id, words in (says or {}).items():
        check = by_id.get(check_id)
        text = f"{check.observed} {check.hint}".lower() if check is not None else ""
        unsaid += [f"{check_id} says {word!r}" for word in words if word.lower() not in text]
    if says:
        expected += "; " + ", ".join(f"{check_id} says {', '.join(map(repr, words))}" for check_id, words in says.items())
    for wanted in diagnosis or []:
        where = [c for c in result.checks if not c.passed and (not wanted.check or c.id == wanted.check)]
        if not any(d.kind == wanted.kind and all(d.mentions(word) for word in wanted.mentions)
                   for c in where for d in c.diagnosis):
            unsaid.append(f"a {wanted.kind} diagnosis" + (f" of {wanted.check}" if wanted.check else "")
                          + (f" naming {', '.join(wanted.mentions)}" if wanted.mentions else ""))
    if diagnosis:
        expected += "; diagnosed: " + ", ".join(d.kind for d in diagnosis)
    if unsaid:
        expected += f" (missing: {'; '.join(unsaid)})"
    ok = not unknown and not wrong_list and not unsaid and result.score < result.max_score and len(lost) == len(fails)
    return ok, expected


def fixture_note(fails: list[str], skips: list[str], result: LessonResult) -> str:
    """What a wrong solution lost beyond the checks its fixture names (a note, not a failure):
    ``"also lost: a, b; also not checked: c"``, or "" when nothing.

    A judged check that lost points is "lost"; a check not judged because a check it needs
    failed is "not checked"; each only when neither ``fails`` nor ``skips`` names it.
    """
    named = set(fails) | set(skips)
    lost = [c.id for c in result.checks if not c.passed and not c.skipped and c.id not in named]
    unchecked = [c.id for c in result.checks if c.skipped and c.id not in named]
    parts = ([f"also lost: {', '.join(lost)}"] if lost else []) + \
        ([f"also not checked: {', '.join(unchecked)}"] if unchecked else [])
    return "; ".join(parts)


def _folders(lesson: Lesson, packages: list[str]) -> set[str]:
    """Source folder names (under ``lesson``'s course's ``solutions/src``) of these packages."""
    found = find_packages(lesson.course.solutions / "src")
    return {found[name][0].name for name in packages if name in found}


def validate_course(lesson_ids: list[str] | None = None, progress: Console | None = None,
                    jobs: int = 1, until_settled: bool = False) -> list[Outcome]:
    """Validate the given lessons (default: all), printing one line per case on ``progress``.

    Args:
        jobs: wrong solutions of a lesson graded at once (:func:`validate_lesson`); 1: one at a time.
        until_settled: grade each wrong solution and the starter only until their verdicts are settled
            (``--until-settled``).

    Raises:
        CourseError: ``jobs`` < 1.  UnknownLesson: a lesson id is not in the catalog.
    """
    if jobs < 1:
        raise CourseError(f"--jobs must be 1 or more (got {jobs})", "e.g. --jobs 2: two wrong solutions at once")
    catalog = load_catalog()
    lessons = [catalog.get(i) for i in lesson_ids] if lesson_ids else catalog.lessons
    outcomes = []
    for lesson in lessons:
        if progress is not None:
            progress.print(f"validating {lesson.id} ...")
        contract = contract_outcome(lesson)
        if contract is None:
            if progress is not None:
                progress.print(f"  [yellow]warning[/] {lesson.id}: {NO_CONTRACT} "
                               f"({lesson.folder.name}/contract.yaml is missing)")
        else:
            outcomes.append(contract)
            if progress is not None:
                mark = "[green]ok[/]" if contract.ok else "[red]WRONG[/]"
                progress.print(f"  {mark} {contract.case}: {escape(contract.got)}")
                for problem in contract.problems:
                    progress.print(f"    {problem}", markup=False, soft_wrap=True)
        for outcome in validate_lesson(lesson, jobs, until_settled):
            outcomes.append(outcome)
            if progress is not None:
                mark = "[green]ok[/]" if outcome.ok else "[red]WRONG[/]"
                progress.print(f"  {mark} {escape(outcome.line())}")
    return outcomes


#: Markers around the generated lesson table in a course's README (:func:`lessons_markdown`).
TABLE_BEGIN, TABLE_END = "<!-- lessons: begin (generated: python benchmarks/grader_strength.py --readme) -->", \
    "<!-- lessons: end -->"


def lessons_markdown() -> str:
    """A Markdown table of the course's lessons, in order: id, title, checks and points of its grader,
    wrong solutions (fixtures), grader strength (its last ``dev mutate``, :func:`~ros2course.dev.mutants.score_text`)
    and the reference's steadiness (its last repeat run, :func:`~ros2course.dev.strength.steadiness_text`).

    Raises:
        CourseError: a grader cannot be imported.  LessonFormatError: a fixture is malformed.
    """
    rows = ["| lesson | title | checks (points) | wrong solutions | grader strength | reference steadiness |",
            "|---|---|---:|---:|---|---|"]
    for lesson in load_catalog().lessons:
        checks = load_grader(lesson.grader).CHECKS
        title = lesson.title.replace("|", "\\|")
        rows.append(f"| `{lesson.id}` | {title} | {len(checks)} ({sum(c.points for c in checks):g}) | "
                    f"{len(load_fixtures(lesson.id))} | {score_text(lesson)} | {steadiness_text(lesson)} |")
    return "\n".join(rows)


def with_lessons_table(readme: str) -> str:
    """``readme`` with the text between :data:`TABLE_BEGIN` and :data:`TABLE_END` replaced by :func:`lessons_markdown`.

    Raises:
        CourseError: the README has no such markers.
    """
    try:
        head, rest = readme.split(TABLE_BEGIN, 1)
        _, tail = rest.split(TABLE_END, 1)
    except ValueError as exc:
        raise CourseError("the README has no generated lesson table",
                          f"put the two lines {TABLE_BEGIN!r} and {TABLE_END!r} where it goes") from exc
    return f"{head}{TABLE_BEGIN}\n{lessons_markdown()}\n{TABLE_END}{tail}"


def render_outcomes(outcomes: list[Outcome], console: Console) -> None:
    """Table of every case, what the failed checks of each WRONG case observed, then a one-line summary."""
    table = Table(title="ros2course dev validate", title_justify="left")
    for column in ("lesson", "case", "", "expected", "got"):
        table.add_column(column, overflow="fold")
    for o in outcomes:
        table.add_row(o.lesson, o.case, "[green]ok[/]" if o.ok else "[red]WRONG[/]", escape(o.expected),
                      escape(o.got + (f"; {o.note}" if o.note else "")))
    console.print(table)
    for o in outcomes:  # what each failed check of a WRONG case observed: a flaky check is diagnosed from this
        for problem in o.problems:  # a contract.yaml's problems, path:line: message
            console.print(f"  {o.lesson} {o.case}: {problem}", markup=False, soft_wrap=True)
        if not o.ok and o.result is not None:
            for check in o.result.checks:
                if not check.passed:
                    console.print(f"  {o.lesson} {o.case}: {check.id}: {check.observed[:400]}", markup=False)
    bad = sum(not o.ok for o in outcomes)
    console.print(f"{len(outcomes) - bad} passed, {bad} failed")

    catalog = load_catalog()
    for lesson_id in dict.fromkeys(o.lesson for o in outcomes):
        if lesson_id in catalog.ids():
            console.print(describe_score(catalog.get(lesson_id)), markup=False)
            # rules covering a contract requirement's line, records of another grader fingerprint (issue 37);
            # a rule or entry matching no mutant is reported by `dev mutate`, which generates them
            for problem in triage_problems(catalog.get(lesson_id)):
                console.print(f"  {lesson_id}: mutation triage: {problem}", markup=False, soft_wrap=True)

