"""``ros2course dev validate --batch``: a class graded with ``grade`` gets the verdicts ``check`` gives.

``check`` grades the learner's own workspace as the learner; ``grade`` grades a
copy, as a fresh unprivileged uid inside namespaces, with the course's own build
of the interfaces its graders import (:mod:`ros2course.batch.runner`). Whatever
differs between the two paths (a folder the submission's uid cannot write, an
interface package not built for the batch) shows up as a correct submission
losing points in batch only, and nothing but a class's grades would show it.

So the course proves parity: after ``dev validate`` has graded each lesson's
reference and wrong solutions through ``check``
(:func:`ros2course.dev.validate.validate_course`), :func:`batch_parity` hands the
reference and a sample of the wrong solutions in as one class (one student per
lesson and case, each graded for its own lesson only), grades it with
:func:`ros2course.batch.runner.run_batch` with the isolation this machine gives
(full isolation as root), and fails every case whose status, score or set of
failed checks differs from the ``check`` result of the same case. A wrong solution that differs is graded
once more with ``check``: when that run gives ``grade``'s verdict and what changed between ``check``'s two
runs is no check its fixture names, the difference is the wrong program's own race, not parity
(:func:`own_race`), and the case passes saying so. When ``check`` gives its first verdict again, the case is
graded once more through ``grade``: a difference ``grade`` does not repeat either was one run's race of the
wrong program and the grader (CI of stop 72: gazebo-custom-nodes' ``thrust-ctrl-c-uncaught`` passed its
Ctrl+C check once under ``grade``; 6 of 6 ``grade`` runs failed it afterwards), and the case passes saying so;
a difference either path repeats fails.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from ros2course.dev import first_line
from ros2course.dev.child import grade_in_child
from ros2course.batch.runner import run_batch
from ros2course.builder.reference import reference_workspace
from ros2course.grade.checklist import StopWhen
from ros2course.grade.results import LessonResult
from ros2course.dev.validate import (
    Outcome,
    apply_edits,
    load_fixtures,
    run_commands,
    unjudged,
    validate_course,
)
from ros2course.lesson.catalog import Lesson, load_catalog

#: Suffix of the parity rows' case names in ``dev validate`` output.
BATCH_CASE = " (grade)"


def sample_fixtures(lesson: Lesson, count: int, checked: list[Outcome] | None = None) -> list[str]:
    """Names of ``count`` of the lesson's fixtures to hand in to the batch (all when fewer).

    With ``checked`` (the lesson's ``dev validate`` outcomes), the sample is the
    wrong solutions ``check`` graded (status passed or failed: their checks ran,
    so the batch's verdict is compared check by check) fastest: any one proves
    that ``grade`` loses the points ``check`` lost, and the quick ones spare the
    batch a script's 25-s timeout. One ``--until-settled`` stopped is as good as
    one graded whole (the batch stops it too, and compares the checks it judged;
    the reference, graded whole by both, compares every check). Without
    ``checked``, or when too few were graded, the names are spread evenly over
    the sorted fixtures.
    """
    names = [f.name for f in load_fixtures(lesson.id)]
    if count >= len(names):
        return names
    if count <= 0:
        return []
    # a wrong solution whose program died on its own (a `process` diagnosis) last, whatever else: what was
    # observed of it depends on how far it got before it died (its node name is seen or not; a state query
    # answered or not), a race, not parity (CI of 7b4b111: lifecycle-node's timer-made-in-activate, graded whole,
    # was picked and lost 'shutdown' under grade only); then the fastest, stopped or whole: its time is the
    # batch's (preferring one graded whole cost the CI run up to 25 s a lesson: 48.0 min on 2 cores)
    graded = sorted((o for o in checked or [] if o.lesson == lesson.id and o.case in names
                     and o.result is not None and o.result.status.graded),
                    key=lambda o: (_died_on_its_own(o), o.seconds))
    if len(graded) >= count:
        return [o.case for o in graded[:count]]
    step = len(names) / count
    return [names[int(i * step)] for i in range(count)]


def _died_on_its_own(outcome: Outcome) -> bool:
    """True when a check of ``outcome`` was diagnosed ``process``: a learner process ended before the grader
    stopped it (:func:`ros2course.run.diagnose.process_findings`)."""
    return any(d.kind == "process" for c in outcome.result.checks for d in c.diagnosis)


def case_workspace(lesson: Lesson, case: str, dest: Path) -> Path:
    """A whole workspace as a student hands it in for ``case`` (``reference`` or a fixture's name).

    Unlike a ``dev validate`` case (built on an underlay of the lesson's dependencies), it holds
    every package the lesson needs, as a student's workspace does; no ``build/``/``install/``/``log/``
    unless the lesson's reference commands make them (``workspace-setup`` hands in the build it grades).

    Raises:
        LessonFormatError: no fixture of that name, or its edits do not apply.
    """
    reference_workspace(lesson, dest)
    commands = lesson.reference.commands
    if case != "reference":
        fixture = {f.name: f for f in load_fixtures(lesson.id)}[case]
        apply_edits(dest, fixture.edits)
        if fixture.commands is not None:
            commands = fixture.commands
    run_commands(dest, commands)
    return dest


def _verdict(result: LessonResult) -> tuple[str, float, tuple[str, ...]]:
    return str(result.status), round(result.score, 6), tuple(sorted(result.failed_checks()))


def same_verdicts(checked: LessonResult, batch: LessonResult) -> bool:
    """``grade``'s result gives ``check``'s verdicts: the same status, score and failed checks; or, when
    ``check`` stopped early (``dev validate --until-settled``: checks "not checked: " +
    :data:`~ros2course.grade.checklist.STOPPED_SETTLED`), the same status and, check by check, the same
    points, pass and skip on every check both judged (the batch stops there too: :func:`batch_parity`)."""
    cut = unjudged(checked)
    if not cut:
        return _verdict(batch) == _verdict(checked)
    cut |= unjudged(batch)  # the batch stopped too (its hand-in settled by the same checks): judged by both

    def judged(result: LessonResult) -> list[tuple[str, float, bool, bool]]:
        return [(c.id, round(c.points, 6), c.passed, c.skipped) for c in result.checks if c.id not in cut]

    return batch.status == checked.status and judged(batch) == judged(checked)


def differing_checks(first: LessonResult, second: LessonResult) -> list[str]:
    """Ids of the checks both results judged (neither "not checked" by ``--until-settled``) whose points, pass
    or skip differ, in ``first``'s order."""
    cut = unjudged(first) | unjudged(second)
    other = {c.id: (round(c.points, 6), c.passed, c.skipped) for c in second.checks}
    return [c.id for c in first.checks if c.id not in cut and c.id in other
            and other[c.id] != (round(c.points, 6), c.passed, c.skipped)]


def own_race(checked: LessonResult, batch: LessonResult, again: LessonResult | None,
             named: tuple[str, ...]) -> list[str]:
    """The checks a wrong solution's own race decides, not parity: [] unless ``check`` graded it ``again`` and
    got ``grade``'s verdict (:func:`same_verdicts`) where its first run (``checked``) got another, and none of
    the checks that changed between ``check``'s two runs is one the fixture ``named`` (its ``fails``,
    ``skips``, ``says``: what it claims to prove).

    Why: a wrong program may race itself (main() called at import sends a second goal a second after the
    first; a leaked timer crashes the process before or after a query is answered), so a check its fixture does
    not name gets either verdict in either path (CI of 7b4b111, 4dd929d and 893e21c each failed one such
    case). ``grade`` giving a verdict ``check`` gives too is parity; a difference on a named check, or one
    ``check`` does not reproduce, still fails.
    """
    if again is None or not same_verdicts(again, batch):
        return []
    changed = differing_checks(checked, again)
    return [] if not changed or set(changed) & set(named) else changed


def _grade_again(root: Path, student: str, lesson: str, student_lessons: dict[str, list[str]],
                 stop_when: dict[str, StopWhen]) -> LessonResult | None:
    """``student``'s submission (in ``root``/submissions) graded once more through ``grade``, alone in a batch of
    its own; None when the batch gave no result."""
    lone, out = root / "again-batch" / student / "submissions", root / "again-batch" / student / "out"
    lone.mkdir(parents=True)
    for folder in (lone.parent, lone):
        folder.chmod(0o755)
    shutil.copytree(root / "submissions" / student, lone / student, symlinks=True)
    report = run_batch(lone, [lesson], out, jobs=1, student_lessons={student: student_lessons[student]},
                       stop_when={k: v for k, v in stop_when.items() if k == student})
    return next((r for r in report.records if r.student == student and r.lesson == lesson), None)


def _describe(result: LessonResult) -> str:
    text = f"{result.status} {result.score:g}/{result.max_score:g}; failed: {', '.join(result.failed_checks()) or 'none'}"
    if result.message and not result.status.graded:
        text += f"; {first_line(result.message)}"
    return text


def batch_parity(lessons: list[Lesson], checked: list[Outcome], jobs: int = 1, progress=None) -> list[Outcome]:
    """Grade the ``checked`` cases of ``lessons`` again through ``grade`` (one batch); one outcome per case.

    Args:
        lessons: the lessons whose cases are in ``checked``.
        checked: ``dev validate`` outcomes (each with its ``check`` result) of the cases to hand in:
            typically each lesson's reference and a sample of its fixtures (:func:`sample_fixtures`).
        jobs: submissions graded at once.
        progress: a rich Console for one line per case (None: quiet).

    Returns:
        one :class:`~ros2course.dev.validate.Outcome` per case, named ``<case> (grade)``: ok when the batch's
        status, score and failed checks equal ``check``'s (``expected`` is the check result, ``got`` the batch's).

    Raises:
        CourseError: the batch refuses the lessons (e.g. an interface package the course cannot build).
    """
    by_id = {lesson.id: lesson for lesson in lessons}
    cases = [o for o in checked if o.result is not None and o.lesson in by_id]
    if not cases:
        return []
    root = Path(tempfile.mkdtemp(prefix="ros2course-parity-"))
    root.chmod(0o755)
    try:
        submissions, out_dir = root / "submissions", root / "out"
        submissions.mkdir()
        student_lessons: dict[str, list[str]] = {}
        stop_when: dict[str, StopWhen] = {}
        fixtures: dict[str, dict] = {}  # lesson id -> its fixtures by name, read once
        names: dict[str, Outcome] = {}
        for outcome in cases:
            student = f"{outcome.lesson}.{outcome.case}"
            case_workspace(by_id[outcome.lesson], outcome.case, submissions / student)
            student_lessons[student] = [outcome.lesson]
            names[student] = outcome
            if unjudged(outcome.result):  # check stopped once the fixture's checks were judged: so does grade
                if outcome.lesson not in fixtures:
                    fixtures[outcome.lesson] = {f.name: f for f in load_fixtures(outcome.lesson)}
                fixture = fixtures[outcome.lesson].get(outcome.case)
                if fixture is not None and fixture.judged_by():
                    stop_when[student] = StopWhen(frozenset(fixture.judged_by()))
        report = run_batch(submissions, list(by_id), out_dir, jobs=jobs, student_lessons=student_lessons,
                           stop_when=stop_when)
        graded = {(r.student, r.lesson): r for r in report.records}
        out: list[Outcome] = []
        for student, checked_case in names.items():
            want = checked_case.result
            got = graded.get((student, checked_case.lesson))
            ok = got is not None and same_verdicts(want, got)
            said = _describe(got) if got is not None else "no result from the batch"
            if checked_case.lesson not in fixtures:
                fixtures[checked_case.lesson] = {f.name: f for f in load_fixtures(checked_case.lesson)}
            fixture = fixtures[checked_case.lesson].get(checked_case.case)
            if not ok and got is not None and fixture is not None and fixture.expect == "fail":
                # a wrong solution: is the difference its own race? check grades it once more, as it did
                again = grade_in_child(checked_case.lesson, case_workspace(
                    by_id[checked_case.lesson], checked_case.case, root / "again" / student), (),
                    root / "again-logs" / student, stop_when=stop_when.get(student))
                raced = own_race(want, got, again, fixture.judged_by() or tuple(fixture.fails))
                if raced:
                    ok = True
                    said += (f"; check's second run gave this verdict too: {', '.join(raced)} changed between "
                             "check's two runs (this wrong solution races itself on checks its fixture does not "
                             "name: not parity)")
                elif again is not None and same_verdicts(want, again):
                    # check gives its verdict twice: does grade give it on a second run? (a difference that
                    # does not repeat is one run's race, not the two paths' difference)
                    second = _grade_again(root, student, checked_case.lesson, student_lessons, stop_when)
                    if second is not None and same_verdicts(want, second):
                        ok = True
                        said += (f"; grade's second run gave check's verdict ({', '.join(differing_checks(want, got))}"
                                 " differed in its first run only: this wrong solution's bug was missed in one run, a "
                                 "race of the program and the grader, not parity)")
            outcome = Outcome(checked_case.lesson, checked_case.case + BATCH_CASE, ok, "as check: " + _describe(want),
                              said, float(got.timings.get("total", 0.0)) if got is not None else 0.0, got)
            out.append(outcome)
            if progress is not None:
                mark = "[green]ok[/]" if ok else "[red]WRONG[/]"
                progress.print(f"  {mark} {outcome.case}: {outcome.got}")
        return out
    finally:
        shutil.rmtree(root, ignore_errors=True)


def validate_with_batch(lesson_ids: list[str] | None, sample: int = 2, jobs: int = 1, progress=None,
                        until_settled: bool = False) -> list[Outcome]:
    """``dev validate --batch``: every case through ``check`` (:func:`ros2course.dev.validate.validate_course`),
    then the reference and ``sample`` fixtures of each lesson through ``grade`` in one batch
    (:func:`batch_parity`); the outcomes of both, the batch's last. ``jobs``: wrong solutions
    graded at once by ``check`` (:func:`~ros2course.dev.validate.validate_lesson`); the batch grades
    up to two submissions at once when ``jobs`` > 1 (a reference beside one wrong solution: every reference
    keeps its verdicts two at once, ``benchmarks/grader_strength.py --repeat 20 --load 2``; one at a time,
    the batch's two cases took 54 s of inspect-params' 183-s validation, and CI's run of stop 73 46 min).
    ``until_settled``: ``check`` grades each wrong solution only until its named checks are judged
    (``--until-settled``); the batch's verdicts are compared on those checks (:func:`same_verdicts`).

    Raises:
        UnknownLesson: a lesson id is not in the catalog.  CourseError: the batch refuses a lesson.
    """
    catalog = load_catalog()
    lessons = [catalog.get(i) for i in lesson_ids] if lesson_ids else catalog.lessons
    outcomes = validate_course([lesson.id for lesson in lessons], progress=progress, jobs=jobs, until_settled=until_settled)
    picks = {lesson.id: {"reference", *sample_fixtures(lesson, sample, outcomes)} for lesson in lessons}
    checked = [o for o in outcomes if o.case in picks.get(o.lesson, ())]
    if progress is not None:
        progress.print(f"grading {len(checked)} case(s) of {len(lessons)} lesson(s) again with ros2course grade ...")
    return outcomes + batch_parity(lessons, checked, jobs=min(jobs, 2), progress=progress)
