"""``ros2course grade``: isolated, parallel, resumable grading of a whole class.

One submission is one *job* (:class:`Job`), run by :func:`run_job`:

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
import functools
import json
import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import psutil
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table

from ros2course.batch.archive import Submission, discover, prepare
from ros2course.build.reference import (
    ReferenceBuild,
    lesson_dependencies,
    shared_reference_build,
    trusted_interface_packages,
)
from ros2course.errors import CourseError, MissingRequirement, NotGradable
from ros2course.files import atomic_write_text
from ros2course.grade.engine import load_grader
from ros2course.grade.results import LessonResult, Status
from ros2course.lesson.catalog import content_root, load_catalog
from ros2course.lesson.courses import course_fixtures
from ros2course.report import gradebook
from ros2course.ros import env as env_mod
from ros2course import sandbox
from ros2course.run.process import OutputDrain, kill_marked, sweep_stale_fastdds_shm

#: Environment variable every process of a job carries (its value: the job's marker).
BATCH_MARKER_VAR = "ROS2COURSE_BATCH_MARKER"
#: Default wall-clock limit per submission (all its lessons), seconds.
DEFAULT_TIMEOUT = 300.0
#: Default address-space limit per process of a submission, bytes (rclpy + Fast DDS need ~1.5 GiB).
DEFAULT_MEMORY_LIMIT = 4 * 1024**3
#: Largest file a submission's processes may write, bytes.
DEFAULT_FILE_LIMIT = 512 * 1024**2
#: Bytes of the worker's own stdout+stderr kept in ``logs/worker.log``.
DEFAULT_OUTPUT_CAP = 2_000_000

_cancelled: set[str] = set()
_isolation_lock = threading.Lock()
_isolation_cache: dict[str, Any] = {}


@dataclasses.dataclass
class Job:
    """Everything :func:`run_job` needs (plain data: it travels to Dask workers by pickle).

    Attributes:
        batch_id: the batch's id (cancelling a batch stops its jobs in this process).
        student: student id (output folder name).
        entry: the submission entry (folder or archive), absolute path.
        problem: why the entry cannot be graded at all ("" if it may be).
        lessons: lesson ids to grade, in order.
        out_dir: the batch's OUTDIR (logs go to ``out_dir/<student>/logs``).
        timeout: wall-clock seconds for the whole submission.
        memory_limit: bytes of address space per process (0: no limit).
        file_limit: bytes per written file (0: no limit).
        output_cap: bytes of worker output kept.
        hide: folders hidden from the submission (when a mount namespace is available).
        isolate: use the protections of :mod:`ros2course.sandbox` the machine allows.
        scratch_root: where scratch folders are made (None: the system temp folder).
        pids_limit: tasks (processes + threads) the submission may have at once.
        trusted_interfaces: a built workspace of the course's own interface packages, which the
            grader imports instead of the submission's (its generated code is submission code).
        require_isolation: grade only with every protection in effect (else a "grader error" row).
    """

    batch_id: str
    student: str
    entry: str
    problem: str
    lessons: list[str]
    out_dir: str
    timeout: float = DEFAULT_TIMEOUT
    memory_limit: int = DEFAULT_MEMORY_LIMIT
    file_limit: int = DEFAULT_FILE_LIMIT
    output_cap: int = DEFAULT_OUTPUT_CAP
    hide: list[str] = dataclasses.field(default_factory=list)
    isolate: bool = True
    scratch_root: str | None = None
    pids_limit: int = sandbox.DEFAULT_PIDS_LIMIT
    trusted_interfaces: str = ""
    require_isolation: bool = False


# --- isolation (ros2course.sandbox) -------------------------------------------------------------

def _hideable(folder: Path) -> bool:
    """A folder may be hidden unless it holds what the worker itself needs (Python, this package, HOME)."""
    needed = [Path(sys.prefix), Path(sys.executable).resolve(), Path(__file__).resolve().parents[1], content_root() / "graders",
              content_root() / "chapters"]
    folder = folder.resolve()
    return folder != Path("/") and not any(p.resolve() == folder or p.resolve().is_relative_to(folder) for p in needed)


def default_hidden(submissions: Path, out_dir: Path, scratch_root: Path) -> list[str]:
    """Folders a submission must not see: the other submissions (scratch), the originals, OUTDIR, reference solutions."""
    candidates = [scratch_root, submissions, out_dir, content_root() / "solutions", course_fixtures(content_root())]
    out: list[str] = []
    for folder in candidates:
        folder = folder.resolve()
        if folder.is_dir() and _hideable(folder) and str(folder) not in out:
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
    """The course's own builds of the interface packages the lessons' graders import.

    The grader imports generated message types in its own process; a
    submission's build of them is code the submission controls, so under
    isolation the grader imports these reference builds instead (same
    definitions as the contract in shared/LESSONS.md, so the same wire types).
    Which packages: each lesson's ``interfaces`` and ``references`` (lesson.yaml) and their
    dependencies (:func:`ros2course.build.reference.trusted_interface_packages`).
    Built once and shared while their files and the ROS install stay the same
    (:func:`ros2course.build.reference.shared_reference_build`); call ``discard()`` when done.

    Returns:
        the build (``path``: a workspace with ``install/``), or None when no grader imports interface types.

    Raises:
        CourseError: a lesson declares an interface the course has no package for, or the reference
            packages do not build (a fault of the course or machine).
    """
    packages = trusted_interface_packages(lessons)
    if not packages:
        return None
    return shared_reference_build(lessons[0], packages, "build.log")


def needs_reference_sources(lesson_ids: list[str]) -> bool:
    """True when a lesson's grader reads reference sources (``references:`` in lesson.yaml), which only the
    trusted build brings into the sandbox (``solutions/`` is hidden from submissions and the worker)."""
    catalog = load_catalog()
    return any(catalog.get(lesson_id).references for lesson_id in lesson_ids)


# --- one job ------------------------------------------------------------------------------------

def lesson_checks(lesson_id: str) -> tuple[float, list[str]]:
    """``(max_score, check ids)`` of a lesson's grader.

    Raises:
        UnknownLesson: no such lesson.  CourseError: its grader cannot be imported.
    """
    module = load_grader(load_catalog().get(lesson_id).grader)
    return float(sum(c.points for c in module.CHECKS)), [c.id for c in module.CHECKS]


def _unfinished(lesson_id: str, status: Status, message: str, hint: str = "") -> LessonResult:
    try:
        max_score = lesson_checks(lesson_id)[0]
    except CourseError:
        max_score = 0.0
    return LessonResult.unfinished(lesson_id, status, message, hint, max_score)


def _tree_rss(pid: int) -> int:
    try:
        root = psutil.Process(pid)
        procs = [root, *root.children(recursive=True)]
    except psutil.Error:
        return 0
    total = 0
    for proc in procs:
        with contextlib.suppress(psutil.Error):
            total += proc.memory_info().rss
    return total


def _kill_job(popen: subprocess.Popen, marker: str) -> list[int]:
    """SIGKILL the worker's process group and every process carrying the job's marker."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(popen.pid, signal.SIGKILL)
    return kill_marked(marker, var=BATCH_MARKER_VAR)


def _path_pattern(folder: Path) -> re.Pattern[str]:
    """``folder`` as it appears in a text, ending on a path boundary (``/tmp/a/ws`` never matches ``/tmp/a/ws2``)."""
    return re.compile(re.escape(str(folder)) + r"(?![\w.-])")


def relocate_paths(results: list[LessonResult], moves: Sequence[tuple[Path, str]]) -> list[LessonResult]:
    """The results with the worker's folders named as the instructor sees them.

    A result names the worker's scratch folders in its ``log_dir`` and in its texts
    (observed, hints, messages, build log excerpts). Each string field of each result
    (:meth:`LessonResult.to_record`, walked field by field, never as serialised JSON)
    has every ``(folder, replacement)`` of ``moves`` replaced, in order (list a folder
    before the folders that contain it), matched on path boundaries.

    Args:
        results: the worker's results.
        moves: ``(folder in the worker's scratch, what to show instead)``: e.g. the job's
            ``logs/`` -> ``OUTDIR/<student>/logs``, its ``ws/`` -> ``<submission>``.
    """
    patterns = [(_path_pattern(folder), replacement) for folder, replacement in moves]

    def moved(value: Any) -> Any:
        if isinstance(value, str):
            for pattern, replacement in patterns:
                value = pattern.sub(lambda _: replacement, value)
            return value
        if isinstance(value, dict):
            return {key: moved(item) for key, item in value.items()}
        if isinstance(value, list):
            return [moved(item) for item in value]
        return value

    return [LessonResult.from_record(moved(result.to_record())) for result in results]


@dataclasses.dataclass
class JobResult:
    """What :func:`run_job` gives back for one submission.

    Attributes:
        student: the submission's student id.
        records: one result per lesson graded (none when the job was cancelled: a resumed batch grades it again).
        isolation: the ``isolation`` field of its results (:meth:`ros2course.sandbox.Isolation.to_json`
            plus the memory limit, the pids cgroup's counters and ``killed_after``).
        peak_rss: bytes, the worker and its children at their largest (sampled every 0.5 s).
        seconds: wall time of the job.
        cancelled: the batch was interrupted while it ran.
    """

    student: str
    records: list[LessonResult]
    isolation: dict[str, Any]
    peak_rss: int = 0
    seconds: float = 0.0
    cancelled: bool = False


def run_job(job: Job) -> JobResult:
    """Prepare, grade and clean up one submission; never raises for the submission's faults.

    Returns:
        the job's :class:`JobResult`. Each result carries the student, the isolation,
        ``timings["total"]`` and the peak memory.
    """
    begin = time.monotonic()
    student_logs = Path(job.out_dir) / job.student / "logs"
    scratch = Path(tempfile.mkdtemp(prefix=f"ros2course-grade-{job.student[:40]}-", dir=job.scratch_root))
    scratch.chmod(0o711)  # the submission's uid may pass through to its own ws/, home/ and logs/ros/, nothing else
    isolation: dict[str, Any] = {"netns": False, "mountns": False, "reason": "not run"}
    peak = 0
    cancelled = False
    records: list[LessonResult] = []
    try:
        try:
            ws = prepare(Submission(job.student, Path(job.entry), job.problem), scratch)
        except NotGradable as exc:
            isolation = {"netns": False, "mountns": False, "reason": "not run (not gradable)"}
            records = [_unfinished(lesson, Status.NOT_GRADABLE, exc.message, exc.hint) for lesson in job.lessons]
            ws = None
        if ws is not None:
            records, isolation, peak, cancelled = _run_worker(job, scratch, ws)
        if student_logs.exists():
            shutil.rmtree(student_logs, ignore_errors=True)
        if (scratch / "logs").is_dir():
            # never as links: the submission's uid could write links into logs/ros
            sandbox.copy_logs(scratch / "logs", student_logs)
        records = relocate_paths(records, [(scratch / "logs", str(student_logs)), (scratch / "ws", "<submission>"),
                                           (scratch, "<scratch>")])
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
        if not isolation.get("mountns"):
            sweep_stale_fastdds_shm()
    seconds = time.monotonic() - begin
    for record in records:
        record.student = job.student
        record.isolation = isolation
        record.timings["total"] = round(seconds, 3)
        record.peak_rss = peak
    return JobResult(job.student, [] if cancelled else records, isolation, peak, seconds, cancelled)


def job_walls(job: Job, scratch: Path) -> tuple[list[str], list[str], sandbox.Isolation, sandbox.PidsCgroup | None]:
    """What one job runs inside: ``(command prefix, worker arguments, isolation, pids cgroup)``.

    The prefix is ``unshare`` (network, mount and PID namespaces) + ``dumb-init`` +
    the mount plan (:class:`ros2course.sandbox.MountPlan`), or ``[]``; the worker
    arguments give it the submission's uid, process limit and cgroup. The
    scratch folder's ``ws/``, ``home/`` and ``logs/ros/`` go to that uid.
    """
    (scratch / "home").mkdir(exist_ok=True)
    (scratch / "logs" / "ros").mkdir(parents=True, exist_ok=True)
    if not job.isolate:
        why = "isolation turned off"
        return [], [], sandbox.Isolation({}, {name: why for name in sandbox.PROTECTIONS}), None
    caps = sandbox.capabilities()
    missing = dict(caps.missing)
    protections: dict[str, str | None] = {}
    prefix: list[str] = []
    if caps.unshare:
        read_only = sandbox.read_only_paths() + ([job.trusted_interfaces] if job.trusted_interfaces else [])
        plan = sandbox.MountPlan(caps.tools["ip"], own=str(scratch), hide=job.hide, read_only=read_only, keep=[],
                                 private_tmp=sandbox.PRIVATE_TMP, hidden_home=sandbox.grader_home())
        init = [caps.tools["dumb-init"], "--"] if caps.pidns else []
        prefix = [caps.tools["unshare"], *caps.unshare, *init, "/bin/sh", "-c", plan.script(), "ros2course-ns"]
        protections[sandbox.NETWORK] = "loopback only: no internet, no DDS traffic between submissions"
        protections[sandbox.MOUNTS] = (f"private /dev/shm and {', '.join(sandbox.PRIVATE_TMP)}; "
                                       f"{len(job.hide) + 1} folders hidden (other submissions, OUTDIR, solutions, "
                                       f"the grader's home); course, venv, Python and ROS read-only")
        if caps.pidns:
            protections[sandbox.PIDNS] = "dumb-init is PID 1: every process of the submission ends with the job"
    worker_args: list[str] = []
    uid = None
    cgroup = None
    via = []
    if caps.pids_root:
        try:
            cgroup = sandbox.PidsCgroup(caps.pids_root, job.pids_limit)
            worker_args += ["--pids-cgroup", cgroup.procs]
            via.append("cgroup pids")
        except OSError as exc:
            missing.setdefault(sandbox.PIDS_LIMIT, f"cannot make a pids cgroup: {exc.strerror}")
    if caps.uid_drop:
        uid = sandbox.new_uid()
        for folder in (scratch / "ws", scratch / "home", scratch / "logs" / "ros"):
            sandbox.give_tree(folder, uid)
        (scratch / "home").chmod(0o700)
        # with a cgroup, RLIMIT_NPROC is the backstop just above it (the cgroup counts what it refuses)
        nproc = job.pids_limit + (32 if cgroup is not None else 0)
        worker_args += ["--run-as", f"{uid}:{uid}", "--nproc", str(nproc)]
        protections[sandbox.UID] = f"uid {uid}, no groups, no capabilities, no_new_privs; writes only its scratch copy"
    if uid is not None:
        via.append("RLIMIT_NPROC")
    if via:
        missing.pop(sandbox.PIDS_LIMIT, None)
        protections[sandbox.PIDS_LIMIT] = f"{job.pids_limit} tasks at once ({' + '.join(via)})"
    if job.trusted_interfaces:
        worker_args += ["--trusted-interfaces", job.trusted_interfaces]
    isolation = sandbox.Isolation(protections, missing, uid, job.pids_limit if via else None, " + ".join(via))
    return prefix, worker_args, isolation, cgroup


@functools.lru_cache(maxsize=64)
def _dependencies_of(course: Path, lesson_id: str) -> tuple[str, ...]:
    return tuple(lesson_dependencies(load_catalog().get(lesson_id)))


def _reference_dependencies(lesson_id: str) -> tuple[str, ...]:
    """The reference packages ``lesson_id``'s packages depend on (:func:`~ros2course.build.reference.lesson_dependencies`),
    which the worker builds too when the submission holds them (``grade_lesson(build_also=...)``)."""
    return _dependencies_of(content_root(), lesson_id)


def _run_worker(job: Job, scratch: Path, ws: Path) -> tuple[list[LessonResult], dict[str, Any], int, bool]:
    logs = scratch / "logs"
    logs.mkdir()
    result_file = scratch / "result.json"  # in the root-owned scratch folder: out of the submission's reach
    marker = uuid.uuid4().hex
    prefix, worker_args, walls, cgroup = job_walls(job, scratch)
    if job.require_isolation and walls.missing:
        if cgroup is not None:
            cgroup.close()
        why = "; ".join(f"{name} ({reason})" for name, reason in walls.missing.items())
        return ([_unfinished(lesson, Status.GRADER_ERROR, f"not graded: --require-isolation and missing {why}",
                             "grade on a machine that gives every protection (root, Linux, util-linux, dumb-init)")
                 for lesson in job.lessons], walls.to_json(), 0, False)
    cmd = [sys.executable, "-m", "ros2course.batch.worker", "--workspace", str(ws), "--results", str(result_file),
           "--logs", str(logs), "--memory-limit", str(job.memory_limit), "--file-limit", str(job.file_limit),
           *worker_args]
    for lesson in job.lessons:
        # the course's reference dependencies, read here: solutions/ is hidden from the worker
        cmd += ["--lesson", lesson, "--build-also", f"{lesson}={','.join(_reference_dependencies(lesson))}"]
    isolation = {**walls.to_json(),
                 "memory": f"RLIMIT_AS {job.memory_limit / 2**20:.0f} MiB per process" if job.memory_limit else "none"}
    # parent-death signal: the worker dies with the thread that started it (a pool thread lives as long as
    # the batch), so a SIGKILLed batch leaves no worker behind
    setpriv = shutil.which("setpriv")
    argv = ([setpriv, "--pdeathsig", "KILL"] if setpriv else []) + prefix + cmd
    env = dict(os.environ)
    env.update({BATCH_MARKER_VAR: marker, "HOME": str(scratch / "home"), "ROS_LOG_DIR": str(logs / "ros"),
                "ROS2COURSE_CONTENT": str(content_root()),  # the worker grades on this batch's course
                "PYTHONDONTWRITEBYTECODE": "1", "RCUTILS_COLORIZED_OUTPUT": "0"})
    if walls.uid is not None:
        # Fast DDS's shared-memory segments are made 0644 by their creator, so a grader (root)
        # and a node (the submission's uid) cannot both write them and discovery stalls. DDS
        # over UDP only, inside the job's loopback-only network namespace, works between users.
        profile = scratch / "fastdds-udp-only.xml"
        profile.write_text(sandbox.FASTDDS_UDP_ONLY, encoding="utf-8")
        env.update({"FASTRTPS_DEFAULT_PROFILES_FILE": str(profile), "ROS2COURSE_DISCOVERY_RANGE": "SUBNET"})
    try:
        popen = subprocess.Popen(argv, env=env, cwd=scratch, stdin=subprocess.DEVNULL,  # noqa: S603
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
    except BaseException:
        if cgroup is not None:
            cgroup.close()
        raise
    drain = OutputDrain(popen.stdout, logs / "worker.log", job.output_cap)
    drain.start()
    deadline = time.monotonic() + job.timeout
    peak, next_sample = 0, 0.0
    timed_out = cancelled = False
    while True:
        try:
            popen.wait(timeout=0.1)
            break
        except subprocess.TimeoutExpired:
            pass
        now = time.monotonic()
        if now >= next_sample:
            peak = max(peak, _tree_rss(popen.pid))
            next_sample = now + 0.5
        if now >= deadline:
            timed_out = True
        elif job.batch_id in _cancelled:
            cancelled = True
        if timed_out or cancelled:
            _kill_job(popen, marker)
            with contextlib.suppress(subprocess.TimeoutExpired):
                popen.wait(timeout=10)
            break
    killed = _kill_job(popen, marker)  # whatever is left of it (forked children, escaped sessions)
    if cgroup is not None:
        isolation.update({f"pids_{k}": v for k, v in cgroup.stats().items()})
        cgroup.close()  # kills anything still in it (none, with a PID namespace), then removes it
    drain.join(timeout=5)
    try:
        done = [LessonResult.from_record(d) for d in json.loads(result_file.read_text(encoding="utf-8"))
                if isinstance(d, dict) and d.get("lesson") in job.lessons]
    except (OSError, ValueError, TypeError):
        done = []
    finished = {d.lesson for d in done}
    records = list(done)
    tail = _tail(logs / "worker.log")
    for lesson in job.lessons:
        if lesson in finished:
            continue
        if timed_out:
            records.append(_unfinished(lesson, Status.NOT_GRADABLE, f"timed out after {job.timeout:g} s",
                                       "the submission was stopped: a node that never ends or a build that hangs?"))
        elif not cancelled:
            records.append(_unfinished(lesson, Status.GRADER_ERROR,
                                       f"the grading worker ended with exit code {popen.returncode} before grading "
                                       f"{lesson}" + (f": {tail}" if tail else ""),
                                       "see logs/worker.log; a fault of the grading machine or a limit reached"))
    order = {lesson: i for i, lesson in enumerate(job.lessons)}
    records.sort(key=lambda r: order.get(r.lesson, 0))
    if killed:
        isolation = {**isolation, "killed_after": len(killed)}
    return records, isolation, peak, cancelled


def _tail(path: Path, lines: int = 3) -> str:
    try:
        text = path.read_text(encoding="utf-8", errors="replace").strip().splitlines()
    except OSError:
        return ""
    return " | ".join(line.strip() for line in text[-lines:])[:400]


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
    """

    out_dir: Path
    records: list[LessonResult]
    graded_now: int
    skipped: int
    seconds: float
    isolation: dict[str, Any]
    peak_rss: list[int]


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


def write_outputs(out_dir: Path, records: list[LessonResult], lessons: list[str], students: list[str]) -> None:
    """Rewrite ``gradebook.csv``, ``junit.xml`` and ``<student>/results.json`` of ``students`` (atomically)."""
    latest = gradebook.latest(records)
    columns = _check_columns(sorted({r.lesson for r in latest.values()} | set(lessons),
                                    key=lambda x: (x not in lessons, lessons.index(x) if x in lessons else 0, x)))
    atomic_write_text(out_dir / "gradebook.csv", gradebook.gradebook_csv(latest.values(), columns))
    atomic_write_text(out_dir / "junit.xml", gradebook.junit_xml(latest.values()))
    for student in students:
        mine = [r for (s, _), r in latest.items() if s == student]
        if mine:
            atomic_write_text(out_dir / student / "results.json",
                                   json.dumps(gradebook.gradescope_json(mine), indent=2) + "\n")


def run_batch(submissions: Path, lessons: list[str], out_dir: Path, jobs: int | None = None,
              timeout: float = DEFAULT_TIMEOUT, scheduler: str | None = None, resume: bool = False,
              console: Any = None, memory_limit: int = DEFAULT_MEMORY_LIMIT, isolate: bool = True,
              executor: cf.Executor | None = None, pids_limit: int = sandbox.DEFAULT_PIDS_LIMIT,
              require_isolation: bool = False, student_lessons: dict[str, list[str]] | None = None) -> BatchReport:
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

    Raises:
        CourseError: bad input (no such folder, OUTDIR inside SUBMISSIONS or already
            holding results without ``resume``, unknown lesson, bad numbers), or
            ``require_isolation`` and a protection is missing.
        MissingRequirement: a lesson needs what is not installed.
    """
    begin = time.monotonic()
    submissions = submissions.absolute()
    out_dir = out_dir.absolute()
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
    if require_isolation:
        refuse_without_isolation(isolate)
    catalog = load_catalog()
    for lesson_id in lessons:
        env_mod.require(catalog.get(lesson_id).requires, f"lesson {lesson_id}")
        lesson_checks(lesson_id)
    trusted_interface_packages([catalog.get(lesson_id) for lesson_id in lessons])  # refuses a lesson batch cannot grade
    results_path = out_dir / "results.jsonl"
    existing = gradebook.read_results(results_path)
    if existing and not resume:
        raise CourseError(f"{out_dir} already holds results ({results_path.name})",
                          "add --resume to continue that batch, or choose another --out folder")
    out_dir.mkdir(parents=True, exist_ok=True)
    done = set(gradebook.latest(existing))
    entries = discover(submissions)
    batch_id = uuid.uuid4().hex
    scratch_root = Path(tempfile.mkdtemp(prefix="ros2course-batch-"))
    scratch_root.chmod(0o711)
    hide = default_hidden(submissions, out_dir, scratch_root)
    trusted = None
    if entries and (isolate and sandbox.capabilities().uid_drop or needs_reference_sources(lessons)):
        try:
            trusted = build_trusted_interfaces([catalog.get(lesson) for lesson in lessons])
        except BaseException:
            shutil.rmtree(scratch_root, ignore_errors=True)
            raise
    todo: list[Job] = []
    skipped = 0
    for entry in entries:
        theirs = lessons if student_lessons is None else [l for l in lessons if l in student_lessons.get(entry.student, ())]
        missing = [lesson for lesson in theirs if (entry.student, lesson) not in done]
        if not missing:
            skipped += 1
            continue
        todo.append(Job(batch_id, entry.student, str(entry.path), entry.problem, missing, str(out_dir), timeout,
                        memory_limit, hide=hide, isolate=isolate, scratch_root=str(scratch_root),
                        pids_limit=pids_limit, trusted_interfaces=str(trusted.path if trusted else ""),
                        require_isolation=require_isolation))
    records = list(existing)
    peaks: list[int] = []
    isolation: dict[str, Any] = next((r.isolation for r in reversed(existing)), {})
    if existing:
        write_outputs(out_dir, records, lessons, sorted({r.student for r in existing}))
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
                try:
                    outcome = future.result()
                except Exception as exc:  # noqa: BLE001 - an infrastructure fault is this student's "grader error"
                    failed = [_unfinished(lesson, Status.GRADER_ERROR, f"the job failed: {type(exc).__name__}: {exc}")
                              for lesson in job.lessons]
                    for result in failed:
                        result.student = job.student
                    outcome = JobResult(job.student, failed, {})
                for record in outcome.records:
                    gradebook.append_record(results_path, record)
                    records.append(record)
                if outcome.records:
                    write_outputs(out_dir, records, lessons, [job.student])
                    isolation = outcome.isolation or isolation
                    peaks.append(outcome.peak_rss)
                if progress:
                    progress.update(task, advance=1, last=job.student)
    except BaseException:
        _cancelled.add(batch_id)  # running jobs kill their workers within 0.1 s
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
        _cancelled.discard(batch_id)
        shutil.rmtree(scratch_root, ignore_errors=True)
        if trusted is not None:
            trusted.discard()
    return BatchReport(out_dir, list(gradebook.latest(records).values()), len(todo), skipped,
                       time.monotonic() - begin, isolation, peaks)


def _progress(console: Any):
    if console is None:
        return None
    return Progress(TextColumn("[bold]grading[/]"), BarColumn(), MofNCompleteColumn(), TextColumn("elapsed"),
                    TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
                    TextColumn("[dim]{task.fields[last]}[/]"), console=console, transient=False)


def render_summary(report: BatchReport, console: Any) -> None:
    """Rich tables on ``console``: score distribution, most failed checks, not gradable reasons, isolation."""
    records = report.records
    console.print(f"graded {report.graded_now} submission(s) now, {report.skipped} skipped (--resume), "
                  f"{len(records)} result(s) in {report.out_dir / 'results.jsonl'} ({report.seconds:.1f} s)")
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
