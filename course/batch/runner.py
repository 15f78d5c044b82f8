"""``ros2course grade``: isolated, parallel, resumable grading of a whole class.

One submission is one *job* (:class:`~ros2course.batch.job.Job`), run by
:func:`~ros2course.batch.job.run_job` (:mod:`ros2course.batch.job`):

1. the entry is copied or safely extracted into a fresh scratch folder
   (:mod:`ros2course.batch.archive`); the original is never written to;
2. a worker subprocess (:mod:`ros2course.batch.worker`) grades it with the same
   :func:`ros2course.grade.engine.grade_lesson` as ``check``. It runs in its own
   session, with ``RLIMIT_AS`` / ``RLIMIT_FSIZE`` limits, its output captured
   into a capped log file, and, where the machine allows (``unshare``), in its
   own network namespace (loopback only: no internet, no DDS cross-talk) and
   mount namespace (a private ``/dev/shm`` for Fast DDS, and the other
   submissions, the output folder, the submissions folder and the reference
   solutions hidden under empty tmpfs mounts);
3. the parent enforces the wall-clock timeout: it kills the worker's process
   group and every process carrying the batch's run marker, then sweeps stale
   Fast DDS shared memory;
4. the logs are copied to ``OUTDIR/<student>/logs/`` and the scratch folder removed.

:func:`run_batch` submits the jobs to one ``concurrent.futures`` executor: a
``ThreadPoolExecutor(max_workers=jobs)`` on this machine, or a Dask
distributed cluster's executor (``--scheduler``), whose workers run the same
:func:`run_job` (they need this package, the ROS install and a file system
shared with the parent for the submissions and OUTDIR). The parent alone
writes the outputs (:mod:`ros2course.report.gradebook`) as each job finishes.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import dataclasses
import json
import os
import shutil
import statistics
import sys
import tempfile
import time
import uuid
from collections import Counter
from pathlib import Path
from typing import Any

from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table

from ros2course.batch import provenance
from ros2course.batch.archive import discover
from ros2course.batch.job import (
    DEFAULT_MEMORY_LIMIT,
    DEFAULT_TIMEOUT,
    Job,
    JobResult,
    cancel_batch,
    lesson_checks,
    run_job,
    unfinished_result,
)
from ros2course.builder.reference import (
    ReferenceBuild,
    lesson_dependencies,
    reference_cache_folder,
    shared_reference_build,
    trusted_interface_packages,
)
from ros2course.errors import CourseError, MissingRequirement
from ros2course.files import atomic_write_text
from ros2course.grade.checklist import StopWhen
from ros2course.grade.fingerprint import grader_fingerprint
from ros2course.grade.results import LessonResult, Status
from ros2course.lesson import Course
from ros2course.lesson.catalog import load_catalog
from ros2course.lesson.courses import course_fixtures, course_sources
from ros2course.report import gradebook
from ros2course.ros import env as env_mod
from ros2course import sandbox

# --- isolation (ros2course.sandbox) -------------------------------------------------------------

def _hideable(course: Course, folder: Path) -> bool:
    """A folder may be hidden unless it holds what the worker itself needs (Python, this package, HOME,
    ``course``'s graders and lessons)."""
    needed = [Path(sys.prefix), Path(sys.executable).resolve(), Path(__file__).resolve().parents[1], course.graders,
              course.chapters]
    folder = folder.resolve()
    return folder != Path("/") and not any(p.resolve() == folder or p.resolve().is_relative_to(folder) for p in needed)


#: Folders of a course that only its author reads: hidden from submissions when the course has them.
AUTHOR_FOLDERS = (".git", "docs", "tests", "benchmarks")


#: A lesson's record of its graded mutants (``mutation-outcomes.json``, written by ``ros2course dev mutate``: each
#: names a reference line, original and mutated). The worker never reads it; a submission must not either.
MUTATION_RECORD = "mutation-outcomes.json"


@dataclasses.dataclass(frozen=True)
class SubmissionWalls:
    """What a submission may not see in a batch, worked out once per batch and carried by each job.

    Attributes:
        hide: folders covered by an empty tmpfs (:func:`default_hidden`).
        masked: files bound to ``/dev/null`` (every lesson's :data:`MUTATION_RECORD`), beside
            :data:`ros2course.sandbox.SECRETS`.
    """

    hide: list[str]
    masked: list[str]


def submission_walls(course: Course, submissions: Path, out_dir: Path, scratch_root: Path) -> SubmissionWalls:
    """The folders hidden from and the files masked for every submission of a batch graded on ``course``
    (``grade`` and ``gradescope`` alike): :func:`default_hidden` and the course's mutation records."""
    masked = sorted(str(lesson.folder / MUTATION_RECORD) for lesson in load_catalog(course.root).lessons
                    if (lesson.folder / MUTATION_RECORD).is_file())
    return SubmissionWalls(default_hidden(course, submissions, out_dir, scratch_root), masked)


def default_hidden(course: Course, submissions: Path, out_dir: Path, scratch_root: Path) -> list[str]:
    """Folders a submission must not see: the other submissions (scratch), the originals, OUTDIR, reference solutions
    and wrong ones, the course's :data:`AUTHOR_FOLDERS` (``.git`` holds every version of ``solutions/``), and the
    shared reference builds (:func:`ros2course.builder.reference.reference_cache_folder`: they
    sit in the venv, which is read-only but visible, and hold the reference sources of every lesson a check, a
    validation or an earlier batch built on; the job's own trusted build is bound back read-only, see
    :func:`ros2course.batch.job.job_walls`); for a course merged from a private one
    (:func:`ros2course.lesson.courses.course_folder`), the folders it was made from too: the private course whole,
    the solutions and fixtures of the one it extends."""
    root = course.root
    candidates = [scratch_root, submissions, out_dir, root / "solutions", course_fixtures(root)]
    # a course checked out from git holds every version of solutions/ in .git; its docs (the strength
    # tables list reference lines), tests and benchmarks are the author's, never the worker's
    candidates += [root / name for name in AUTHOR_FOLDERS]
    candidates.append(reference_cache_folder())  # whoever owns it: hidden when it exists
    sources = course_sources(root)
    for index, source in enumerate(sources):
        if index == 0:
            candidates.append(source)  # the private course: its graders and fixtures name the hidden checks
        else:
            candidates += [source / "solutions", course_fixtures(source)]
    out: list[str] = []
    for folder in candidates:
        folder = folder.resolve()
        if folder.is_dir() and _hideable(course, folder) and str(folder) not in out:
            out.append(str(folder))
    return out


def refuse_without_isolation(isolate: bool = True) -> None:
    """Raise unless this machine gives a job every protection of :mod:`ros2course.sandbox`.

    Raises:
        CourseError: one line naming each missing protection and why.
    """
    missing = (sandbox.capabilities().missing if isolate
               else {name: "isolation turned off" for name in sandbox.PROTECTIONS})
    if missing:
        raise CourseError("refusing to grade (--require-isolation): missing "
                          + "; ".join(f"{name} ({why})" for name, why in missing.items()),
                          "run as root on Linux with util-linux, iproute2 and dumb-init, or drop --require-isolation")


def build_trusted_interfaces(lessons: list[Any]) -> ReferenceBuild | None:
    """The course's own builds of the interface packages the lessons' graders import, and of the earlier
    lessons' packages the lessons build on.

    The grader imports generated message types in its own process; a
    submission's build of them is code the submission controls, so under
    isolation the grader imports these reference builds instead (same
    definitions as the contract in shared/LESSONS.md, so the same wire types).
    Which packages: each lesson's ``interfaces`` and ``references`` (lesson.yaml) and their
    dependencies (:func:`ros2course.builder.reference.trusted_interface_packages`), and the reference
    packages its own depend on (:func:`ros2course.builder.reference.lesson_dependencies`): a hand-in that
    holds one of those unchanged is built against this build of it rather than building it again
    (``prebuilt`` of :func:`ros2course.builder.colcon.build_packages`).
    Built once and shared while their files and the ROS install stay the same
    (:func:`ros2course.builder.reference.shared_reference_build`); call ``discard()`` when done.

    Returns:
        the build (``path``: a workspace with ``install/``), or None when no grader imports interface types
        and no lesson builds on an earlier one.

    Raises:
        CourseError: a lesson declares an interface the course has no package for, or the reference
            packages do not build (a fault of the course or machine).
    """
    packages = sorted({*trusted_interface_packages(lessons),
                       *(name for lesson in lessons for name in lesson_dependencies(lesson))})
    if not packages:
        return None
    return shared_reference_build(lessons[0], packages, "build.log")


def needs_reference_sources(lesson_ids: list[str]) -> bool:
    """True when a lesson's grader reads reference sources (``references:`` in lesson.yaml), which only the
    trusted build brings into the sandbox (``solutions/`` is hidden from submissions and the worker)."""
    catalog = load_catalog()
    return any(catalog.get(lesson_id).references for lesson_id in lesson_ids)


# --- the batch -----------------------------------------------------------------------------------

@dataclasses.dataclass
class BatchReport:
    """What a batch did.

    Attributes:
        out_dir: OUTDIR.
        records: every record in ``results.jsonl`` after the batch (latest per student and lesson).
        graded_now: jobs run by this invocation (skipped ones excluded).
        skipped: students skipped by ``--resume``.
        seconds: wall time of the batch, seconds.
        isolation: the isolation of the first job run (or of the resumed records).
        peak_rss: per job run now, bytes.
        regrades: what each regraded row changed (``--regrade``, ``--only``), in the order graded.
    """

    out_dir: Path
    records: list[LessonResult]
    graded_now: int
    skipped: int
    seconds: float
    isolation: dict[str, Any]
    peak_rss: list[int]
    regrades: list[provenance.RegradeChange] = dataclasses.field(default_factory=list)


def make_executor(jobs: int, scheduler: str | None) -> tuple[cf.Executor, Any]:
    """``(executor, client)``: a ``ThreadPoolExecutor(jobs)``, or a Dask client's executor for ``scheduler``.

    Raises:
        MissingRequirement: ``scheduler`` given but ``distributed`` not installed.
        CourseError: the scheduler cannot be reached.
    """
    if not scheduler:
        return cf.ThreadPoolExecutor(max_workers=jobs, thread_name_prefix="ros2course-grade"), None
    try:
        from distributed import Client  # noqa: PLC0415 - optional extra [dask]
    except ImportError as exc:
        raise MissingRequirement("--scheduler needs Dask distributed, which is not installed",
                                 "pip install 'ros2course[dask]'") from exc
    try:
        client = Client(scheduler, timeout=30)
    except (OSError, TimeoutError, ValueError) as exc:
        raise CourseError(f"cannot reach the Dask scheduler {scheduler}: {exc}",
                          "check the address (tcp://HOST:8786) and that the scheduler runs") from exc
    return client.get_executor(pure=False), client


def _check_columns(lessons: list[str]) -> dict[str, list[str]]:
    return {lesson: lesson_checks(lesson)[1] for lesson in lessons}


def write_outputs(out_dir: Path, records: list[LessonResult], lessons: list[str], students: list[str],
                  visibility: dict[str, dict[str, str]] | None = None) -> None:
    """Rewrite ``gradebook.csv``, ``junit.xml`` and ``<student>/results.json`` of ``students`` (atomically).

    ``visibility``: the class file's overrides (:func:`class_visibility`, read once per batch); None reads them."""
    latest = gradebook.latest(records)
    columns = _check_columns(sorted({r.lesson for r in latest.values()} | set(lessons),
                                    key=lambda x: (x not in lessons, lessons.index(x) if x in lessons else 0, x)))
    atomic_write_text(out_dir / "gradebook.csv", gradebook.gradebook_csv(latest.values(), columns))
    atomic_write_text(out_dir / "junit.xml", gradebook.junit_xml(latest.values()))
    overrides = class_visibility(out_dir) if visibility is None else visibility
    for student in students:
        mine = [r.with_visibility(overrides.get(r.lesson, {})) for (s, _), r in latest.items() if s == student]
        if mine:
            atomic_write_text(out_dir / student / "results.json",
                                   json.dumps(gradebook.gradescope_json(mine), indent=2) + "\n")


def class_visibility(out_dir: Path) -> dict[str, dict[str, str]]:
    """``class.yaml``'s ``visibility:`` (lesson id -> check id -> visibility) when OUTDIR holds one, else {}.

    Raises:
        CourseError: the class file is there but bad (:func:`ros2course.report.term.load_class`).
    """
    from ros2course.report.term import CLASS_FILE, load_class  # noqa: PLC0415 - pydantic models, only with a class file

    path = out_dir / CLASS_FILE
    return dict(load_class(path).visibility) if path.is_file() else {}


def _refuse_bad_input(submissions: Path, out_dir: Path, lessons: list[str], jobs: int | None, timeout: float,
                      pids_limit: int) -> dict[str, dict[str, str]]:
    """Refuse a batch before anything is graded (see :func:`run_batch`'s arguments); return the class file's
    visibility overrides (:func:`class_visibility`).

    Raises:
        CourseError: no such folder, OUTDIR inside SUBMISSIONS, no lesson, bad numbers, a lesson
            whose grader does not load or whose interfaces the batch cannot build, a bad OUTDIR/class.yaml.
        MissingRequirement: a lesson needs what is not installed.
    """
    if not submissions.is_dir():
        raise CourseError(f"{submissions} is not a folder", "give the folder that holds one entry per student")
    if out_dir.resolve().is_relative_to(submissions.resolve()):
        raise CourseError(f"OUTDIR {out_dir} is inside the submissions folder", "choose an --out folder elsewhere")
    if not lessons:
        raise CourseError("no lesson given", "add --lesson LESSON (ros2course list shows them)")
    if jobs is not None and jobs < 1:
        raise CourseError(f"--jobs must be at least 1 (got {jobs})", "e.g. --jobs 2")
    if timeout <= 0:
        raise CourseError(f"--timeout must be positive (got {timeout:g})", "e.g. --timeout 300")
    if pids_limit < 16:
        raise CourseError(f"--pids-limit must be at least 16 (got {pids_limit})", "e.g. --pids-limit 256")
    catalog = load_catalog()
    for lesson_id in lessons:
        env_mod.require(catalog.get(lesson_id).requires, f"lesson {lesson_id}")
        lesson_checks(lesson_id)
    trusted_interface_packages([catalog.get(lesson_id) for lesson_id in lessons])  # refuses a lesson batch cannot grade
    return class_visibility(out_dir)  # a bad OUTDIR/class.yaml is refused now, not after the class is graded


def run_batch(submissions: Path, lessons: list[str], out_dir: Path, jobs: int | None = None,
              timeout: float = DEFAULT_TIMEOUT, scheduler: str | None = None, resume: bool = False,
              console: Any = None, memory_limit: int = DEFAULT_MEMORY_LIMIT, isolate: bool = True,
              executor: cf.Executor | None = None, pids_limit: int = sandbox.DEFAULT_PIDS_LIMIT,
              require_isolation: bool = False, student_lessons: dict[str, list[str]] | None = None,
              regrade: str | None = None, only: list[str] | None = None,
              not_taken: dict[str, str] | None = None,
              stop_when: dict[str, StopWhen] | None = None) -> BatchReport:
    """Grade every submission in ``submissions`` for ``lessons``; write OUTDIR as each one finishes.

    Args:
        submissions: folder with one entry per student (see :mod:`ros2course.batch.archive`).
        lessons: lesson ids.
        out_dir: OUTDIR (created).
        jobs: submissions graded at once on this machine (default: number of cores).
        timeout: wall-clock seconds per submission.
        scheduler: a Dask scheduler address; the jobs go to that cluster instead.
        resume: skip (student, lesson) pairs already in ``results.jsonl``.
        console: a rich ``Console`` for the progress bar (None: no progress shown).
        memory_limit: bytes of address space per process of a submission.
        isolate: use the protections of :mod:`ros2course.sandbox` where the machine allows them.
        executor: use this executor instead (tests); ``jobs``/``scheduler`` ignored.
        pids_limit: tasks (processes + threads) each submission may have at once.
        require_isolation: refuse to grade unless every protection is in effect
            (checked here and again by each job, wherever it runs).
        student_lessons: student id -> the lessons (of ``lessons``) that student is graded for
            (default: every lesson for every student; ``dev validate --batch`` hands in one
            workspace per lesson and case).
        regrade: ``changed`` (regrade the rows whose grader fingerprint or submission digest changed since
            they were graded) or ``all`` (every row); None: grade only what has no row yet (with ``resume``).
            See :mod:`ros2course.batch.provenance`.
        only: student ids: grade (and regrade, an appeal) only these students' submissions.
        not_taken: student id -> why the intake could not take their submission (:mod:`ros2course.batch.intake`):
            each gets a "not gradable" row per lesson with that reason, so the gradebook lists the whole class.
        stop_when: student id -> when that submission's grading may stop (the author's tools only, never
            a class: :attr:`~ros2course.batch.job.Job.stop_when`).

    Raises:
        CourseError: bad input (no such folder, OUTDIR inside SUBMISSIONS or already
            holding results without ``resume``/``regrade``/``only``, ``regrade`` without earlier
            results or of an unknown mode, a student of ``only`` not among the submissions, unknown
            lesson, bad numbers), or ``require_isolation`` and a protection is missing.
        MissingRequirement: a lesson needs what is not installed.
    """
    begin = time.monotonic()
    submissions = submissions.absolute()
    out_dir = out_dir.absolute()
    visibility = _refuse_bad_input(submissions, out_dir, lessons, jobs, timeout, pids_limit)
    if require_isolation:
        refuse_without_isolation(isolate)
    catalog = load_catalog()
    results_path = out_dir / "results.jsonl"
    existing = gradebook.read_results(results_path)
    if regrade is not None and regrade not in provenance.REGRADE_MODES:
        raise CourseError(f"unknown --regrade {regrade!r}", "use --regrade changed or --regrade all")
    if regrade is not None and not existing:
        raise CourseError(f"--regrade {regrade}: {out_dir} holds no results to regrade",
                          "give the --out folder of an earlier `ros2course grade`")
    if existing and not (resume or regrade or only):
        raise CourseError(f"{out_dir} already holds results ({results_path.name})",
                          "add --resume to continue that batch, --regrade changed to regrade what changed, "
                          "or choose another --out folder")
    entries = discover(submissions)
    if only:
        unknown = sorted(set(only) - {entry.student for entry in entries})
        if unknown:
            raise CourseError(f"--only: no submission of {', '.join(unknown)} in {submissions}",
                              "give student ids as the submissions folder names them (without .zip)")
        entries = [entry for entry in entries if entry.student in only]
    out_dir.mkdir(parents=True, exist_ok=True)
    provenance.write_run_file(out_dir, submissions, lessons)
    graders = {lesson: grader_fingerprint(catalog.get(lesson)) for lesson in lessons}
    digests = {entry.student: provenance.submission_digest(entry) for entry in entries}
    before_with = provenance.read_graded_with(results_path)
    previous = gradebook.latest(existing)
    why = {(entry.student, lesson): provenance.why_regrade(
               before_with.get((entry.student, lesson)) if (entry.student, lesson) in previous else None,
               graders[lesson], digests[entry.student], regrade, bool(only))
           for entry in entries for lesson in lessons}
    done = {pair for pair in previous if not why.get(pair)}
    batch_id = uuid.uuid4().hex
    scratch_root = Path(tempfile.mkdtemp(prefix="ros2course-batch-"))
    scratch_root.chmod(0o711)
    walls = submission_walls(catalog.course, submissions, out_dir, scratch_root)
    trusted = None
    if entries and (isolate and sandbox.capabilities().uid_drop or needs_reference_sources(lessons)):
        try:
            trusted = build_trusted_interfaces([catalog.get(lesson) for lesson in lessons])
        except BaseException:
            shutil.rmtree(scratch_root, ignore_errors=True)
            raise
    todo: list[Job] = []
    for entry, missing in _to_grade(entries, lessons, student_lessons, done):
        todo.append(Job(batch_id, entry.student, str(entry.path), entry.problem, missing, str(out_dir), timeout,
                        memory_limit, hide=walls.hide, masked=walls.masked, isolate=isolate, scratch_root=str(scratch_root),
                        pids_limit=pids_limit, trusted_interfaces=str(trusted.path if trusted else ""),
                        require_isolation=require_isolation,
                        stop_when=(stop_when or {}).get(entry.student), course=str(catalog.course.root)))
    skipped = len(entries) - len(todo)
    records = list(existing)
    peaks: list[int] = []
    changes: list[provenance.RegradeChange] = []
    logged = 0
    isolation: dict[str, Any] = next((r.isolation for r in reversed(existing)), {})
    for student, reason in sorted((not_taken or {}).items()):
        if only and student not in only:
            continue
        for lesson in lessons:
            if (student, lesson) in previous and not (regrade or only):
                continue
            row = unfinished_result(lesson, Status.NOT_GRADABLE, f"not taken from the download: {reason}",
                                    "hand in again, in the format the course asks for")
            row.student = student
            gradebook.append_record(results_path, row, provenance.graded_with(graders[lesson], "not-taken"))
            records.append(row)
    if existing or not_taken:
        write_outputs(out_dir, records, lessons, sorted({r.student for r in records}), visibility)
    client = None
    own_executor = executor is None
    if own_executor:
        executor, client = make_executor(jobs or os.cpu_count() or 1, scheduler)
    progress = _progress(console)
    try:
        with progress or contextlib.nullcontext():
            task = progress.add_task("grading", total=len(todo), last="") if progress else None
            futures = {executor.submit(run_job, job): job for job in todo}
            for future in cf.as_completed(futures):
                job = futures[future]
                outcome = _outcome(future, job)
                for record in outcome.records:
                    pair = (record.student, record.lesson)
                    now_with = provenance.graded_with(graders.get(record.lesson, ""), digests.get(record.student, ""))
                    old = previous.get(pair)
                    kept = provenance.failed_regrade(record) if old is not None else ""
                    if old is not None:
                        changes.append(provenance.compare(old, record, why.get(pair, ""), before_with.get(pair, {}),
                                                          now_with, kept))
                    if kept:  # a regrade never loses a row: the previous result stays, saying why
                        record = old
                        now_with = {**before_with.get(pair, {}), "regrade_failed": kept}
                    gradebook.append_record(results_path, record, now_with)
                    records.append(record)
                if changes:
                    provenance.append_changes(out_dir, changes[logged:])
                    logged = len(changes)
                if outcome.records:
                    write_outputs(out_dir, records, lessons, [job.student], visibility)
                    if outcome.isolation is not None:  # a job that raised tells nothing of the walls
                        isolation = outcome.isolation.to_json()
                    peaks.append(outcome.peak_rss)
                if progress:
                    progress.update(task, advance=1, last=job.student)
    except BaseException:
        cancel_batch(batch_id)  # running jobs kill their workers within 0.1 s
        for future in futures if "futures" in locals() else ():
            future.cancel()
        if own_executor:
            executor.shutdown(wait=True)
        raise
    finally:
        if own_executor:
            executor.shutdown(wait=True)
            if client is not None:
                client.close()
        cancel_batch(batch_id, cancelled=False)
        shutil.rmtree(scratch_root, ignore_errors=True)
        if trusted is not None:
            trusted.discard()
    return BatchReport(out_dir, list(gradebook.latest(records).values()), len(todo), skipped,
                       time.monotonic() - begin, isolation, peaks, changes)


def _to_grade(entries: list, lessons: list[str], student_lessons: dict[str, list[str]] | None,
              done: set[tuple[str, str]]) -> list[tuple[Any, list[str]]]:
    """``(submission entry, lessons still to grade for it)`` for each entry with any left: its lessons
    (``student_lessons``, else every lesson) less the ``(student, lesson)`` pairs already ``done`` (resume)."""
    pending = []
    for entry in entries:
        theirs = lessons if student_lessons is None else [name for name in lessons if name in student_lessons.get(entry.student, ())]
        missing = [lesson for lesson in theirs if (entry.student, lesson) not in done]
        if missing:
            pending.append((entry, missing))
    return pending


def _outcome(future: cf.Future, job: Job) -> JobResult:
    """The job's result; a job that raised (a fault of the grading machine, never of the submission)
    gives each of its lessons a "grader error" row, so the class report still lists the student."""
    try:
        return future.result()
    except Exception as exc:  # noqa: BLE001 - an infrastructure fault is this student's "grader error"
        failed = [unfinished_result(lesson, Status.GRADER_ERROR, f"the job failed: {type(exc).__name__}: {exc}")
                  for lesson in job.lessons]
        for result in failed:
            result.student = job.student
        return JobResult(job.student, failed, None)


def _progress(console: Any):
    if console is None:
        return None
    return Progress(TextColumn("[bold]grading[/]"), BarColumn(), MofNCompleteColumn(), TextColumn("elapsed"),
                    TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
                    TextColumn("[dim]{task.fields[last]}[/]"), console=console, transient=False)


def render_summary(report: BatchReport, console: Any) -> None:
    """Rich tables on ``console``: score distribution, most failed checks, not gradable reasons, isolation."""
    records = report.records
    console.print(f"graded {report.graded_now} submission(s) now, {report.skipped} skipped (graded before, "
                  f"unchanged), {len(records)} result(s) in {report.out_dir / 'results.jsonl'} ({report.seconds:.1f} s)")
    if report.regrades:
        moved = Counter(change.direction for change in report.regrades)
        console.print(f"regraded {len(report.regrades)} row(s): {moved['up']} up, {moved['down']} down, "
                      f"{moved['same']} unchanged, {moved['kept']} kept (the regrade failed); what changed: "
                      f"{report.out_dir / 'regrades.jsonl'}")
        for change in report.regrades:
            if change.direction != "same":
                checks = ", ".join(f"{cid} {old} -> {new}" for cid, (old, new) in change.checks.items())
                console.print(f"  {change.student} {change.lesson}: {change.old_score:g} -> {change.new_score:g}"
                              f" ({change.why}){': ' + checks if checks else ''}{'; kept: ' + change.kept if change.kept else ''}")
    graded = [r for r in records if r.status.graded]
    if graded:
        table = Table(title="score distribution (percent of max)", title_justify="left")
        table.add_column("lesson")
        table.add_column("range")
        table.add_column("students", justify="right")
        table.add_column("")
        by_lesson: dict[str, list[float]] = {}
        for r in graded:
            by_lesson.setdefault(r.lesson, []).append(100.0 * r.score / r.max_score if r.max_score else 0.0)
        for lesson, scores in by_lesson.items():
            bins = Counter(min(int(s // 20), 4) for s in scores)
            for b in range(5):
                low = b * 20
                label = f"{low}-{low + 20}%" if b < 4 else "80-100%"
                table.add_row(lesson if b == 0 else "", label, str(bins.get(b, 0)), "█" * bins.get(b, 0))
            table.add_row("", "mean / median", f"{statistics.mean(scores):.0f}% / {statistics.median(scores):.0f}%", "")
        console.print(table)
        failed = Counter((r.lesson, c.id) for r in graded for c in r.checks if not c.passed)
        if failed:
            table = Table(title="checks most often failed", title_justify="left")
            table.add_column("lesson")
            table.add_column("check")
            table.add_column("failed by", justify="right")
            for (lesson, check), count in failed.most_common(8):
                table.add_row(lesson, check, f"{count}/{len(by_lesson[lesson])}")
            console.print(table)
    bad = [r for r in records if not r.status.graded]
    if bad:
        table = Table(title="not graded", title_justify="left")
        table.add_column("student")
        table.add_column("lesson")
        table.add_column("status")
        table.add_column("reason", overflow="fold")
        for r in sorted(bad, key=lambda r: (r.student, r.lesson)):
            table.add_row(r.student, r.lesson, r.status.value, r.message.splitlines()[0][:200] if r.message else "")
        console.print(table)
    iso = report.isolation or {}
    table = Table(title="isolation of each submission", title_justify="left")
    table.add_column("protection")
    table.add_column("")
    table.add_column("how, or why missing", overflow="fold")
    protections, missing = iso.get("protections") or {}, iso.get("missing") or {}
    for name in sandbox.PROTECTIONS:
        if protections.get(name):
            table.add_row(name, "[green]in effect[/]", protections[name])
        else:
            table.add_row(name, "[yellow]MISSING[/]", missing.get(name) or iso.get("reason", "no submission run"))
    table.add_row("memory limit", "[green]in effect[/]" if iso.get("memory", "none") != "none" else "[yellow]none[/]",
                  iso.get("memory", "n/a"))
    console.print(table)
    if report.peak_rss:
        console.print(f"peak memory per job: max {max(report.peak_rss) / 2**20:.0f} MiB, "
                      f"mean {statistics.mean(report.peak_rss) / 2**20:.0f} MiB")
