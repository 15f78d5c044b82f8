"""One submission of ``ros2course grade``: a :class:`Job`, run by :func:`run_job`.

1. the entry is copied or safely extracted into a fresh scratch folder
   (:mod:`ros2course.batch.archive`); the original is never written to;
2. a worker subprocess (:mod:`ros2course.batch.worker`) grades it with the same
   :func:`ros2course.grade.engine.grade_lesson` as ``check``, behind the walls
   the machine gives (:func:`job_walls`, :mod:`ros2course.sandbox`);
3. the wall-clock timeout is enforced here: the worker's process group and
   every process carrying the job's marker are killed, then stale Fast DDS
   shared memory is swept;
4. the logs are copied to ``OUTDIR/<student>/logs/``, the results' paths
   relocated there (:func:`relocate_paths`), the scratch folder removed.

A job is plain data (it travels to Dask workers by pickle); :mod:`ros2course.batch.runner`
runs a class's jobs and writes the outputs.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import psutil

from ros2course.batch.archive import Submission, prepare
from ros2course.builder.reference import lesson_dependencies
from ros2course.errors import CourseError, NotGradable
from ros2course.grade.checklist import StopWhen
from ros2course.grade.engine import load_grader
from ros2course.grade.results import LessonResult, Status
from ros2course.lesson.catalog import load_catalog
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

#: Ids of the batches being interrupted: their running jobs kill their workers (:func:`cancel_batch`).
_cancelled: set[str] = set()


def cancel_batch(batch_id: str, cancelled: bool = True) -> None:
    """Mark batch ``batch_id`` interrupted (its running jobs kill their workers within 0.1 s and
    return no records), or, with ``cancelled=False``, forget it once the batch has ended."""
    if cancelled:
        _cancelled.add(batch_id)
    else:
        _cancelled.discard(batch_id)


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
        masked: files shown to the submission as empty (``/dev/null`` bound over them), beside
            :data:`ros2course.sandbox.SECRETS`; ``hide`` and ``masked`` come from
            :func:`ros2course.batch.runner.submission_walls`.
        isolate: use the protections of :mod:`ros2course.sandbox` the machine allows.
        scratch_root: where scratch folders are made (None: the system temp folder).
        pids_limit: tasks (processes + threads) the submission may have at once.
        trusted_interfaces: a built workspace of the course's own interface packages, which the
            grader imports instead of the submission's (its generated code is submission code).
        require_isolation: grade only with every protection in effect (else a "grader error" row).
        stop_when: when each lesson's grading may stop, the checks after it "not checked"
            (:class:`~ros2course.grade.checklist.StopWhen`): the author's tools only, never a class's batch
            (``dev validate --batch --until-settled``: once a wrong solution's named checks are judged;
            ``dev mutate --first-loss``: at a mutant's first lost point); None: graded whole.
        course: the course folder the submission is graded on, resolved once by the command that made the
            batch (the worker is told it through ``ROS2COURSE_CONTENT``; the sandbox shows it read-only).
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
    masked: list[str] = dataclasses.field(default_factory=list)
    isolate: bool = True
    scratch_root: str | None = None
    pids_limit: int = sandbox.DEFAULT_PIDS_LIMIT
    trusted_interfaces: str = ""
    require_isolation: bool = False
    stop_when: StopWhen | None = None
    course: str = ""

    def __post_init__(self) -> None:
        if not self.course:  # a worker told no course would grade on whatever course its process finds
            raise ValueError("a batch Job names the course folder its submission is graded on (course=...)")


# --- one job ------------------------------------------------------------------------------------

def lesson_checks(lesson_id: str) -> tuple[float, list[str]]:
    """``(max_score, check ids)`` of a lesson's grader.

    Raises:
        UnknownLesson: no such lesson.  CourseError: its grader cannot be imported.
    """
    module = load_grader(load_catalog().get(lesson_id).grader)
    return float(sum(c.points for c in module.CHECKS)), [c.id for c in module.CHECKS]


def unfinished_result(lesson_id: str, status: Status, message: str, hint: str = "") -> LessonResult:
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
        isolation: what protected it (its results carry :meth:`~ros2course.sandbox.Isolation.to_json`);
            None when the job itself raised (:func:`ros2course.batch.runner.run_batch` makes its rows).
        peak_rss: bytes, the worker and its children at their largest (sampled every 0.5 s).
        seconds: wall time of the job.
        cancelled: the batch was interrupted while it ran.
    """

    student: str
    records: list[LessonResult]
    isolation: sandbox.Isolation | None
    peak_rss: int = 0
    seconds: float = 0.0
    cancelled: bool = False


def _packages_needed(lesson_ids: Sequence[str]) -> bool:
    """Whether a lesson among ``lesson_ids`` has packages of its own (``packages:`` in its lesson.yaml), so that a
    hand-in without any is not gradable for it (:func:`ros2course.batch.archive.prepare`); an id the catalog
    does not know counts as needing them (the batch reports it elsewhere)."""
    catalog = load_catalog()
    for lesson_id in lesson_ids:
        try:
            if catalog.get(lesson_id).packages:
                return True
        except CourseError:
            return True
    return False


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
    isolation = sandbox.Isolation.never_ran("not run")
    peak = 0
    cancelled = False
    records: list[LessonResult] = []
    try:
        try:
            ws = prepare(Submission(job.student, Path(job.entry), job.problem), scratch,
                         packages_needed=_packages_needed(job.lessons))
        except NotGradable as exc:
            isolation = sandbox.Isolation.never_ran("not run (not gradable)")
            records = [unfinished_result(lesson, Status.NOT_GRADABLE, exc.message, exc.hint) for lesson in job.lessons]
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
        if not isolation.mount_namespace:
            sweep_stale_fastdds_shm()
    seconds = time.monotonic() - begin
    for record in records:
        record.student = job.student
        record.isolation = isolation.to_json()
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
        read_only = sandbox.read_only_paths(Path(job.course)) + ([job.trusted_interfaces] if job.trusted_interfaces else [])
        plan = sandbox.MountPlan(caps.tools["ip"], own=str(scratch), hide=job.hide, read_only=read_only, keep=[],
                                 private_tmp=sandbox.PRIVATE_TMP, hidden_home=sandbox.grader_home(),
                                 secrets=sandbox.SECRETS + tuple(job.masked))
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
def _reference_dependencies(course: Path, lesson_id: str) -> tuple[str, ...]:
    """The reference packages ``lesson_id``'s packages depend on (:func:`~ros2course.builder.reference.lesson_dependencies`),
    in the course at ``course``, which the worker builds too when the submission holds them
    (``grade_lesson(build_also=...)``)."""
    return tuple(lesson_dependencies(load_catalog(course).get(lesson_id)))


def _run_worker(job: Job, scratch: Path, ws: Path) -> tuple[list[LessonResult], sandbox.Isolation, int, bool]:
    logs = scratch / "logs"
    logs.mkdir()
    result_file = scratch / "result.json"  # in the root-owned scratch folder: out of the submission's reach
    marker = uuid.uuid4().hex
    prefix, worker_args, walls, cgroup = job_walls(job, scratch)
    if job.require_isolation and walls.missing:
        if cgroup is not None:
            cgroup.close()
        why = "; ".join(f"{name} ({reason})" for name, reason in walls.missing.items())
        return ([unfinished_result(lesson, Status.GRADER_ERROR, f"not graded: --require-isolation and missing {why}",
                             "grade on a machine that gives every protection (root, Linux, util-linux, dumb-init)")
                 for lesson in job.lessons], walls, 0, False)
    cmd = [sys.executable, "-m", "ros2course.batch.worker", "--workspace", str(ws), "--results", str(result_file),
           "--logs", str(logs), "--memory-limit", str(job.memory_limit), "--file-limit", str(job.file_limit),
           *worker_args]
    for lesson in job.lessons:
        # the course's reference dependencies, read here: solutions/ is hidden from the worker
        cmd += ["--lesson", lesson, "--build-also", f"{lesson}={','.join(_reference_dependencies(Path(job.course), lesson))}"]
    if job.stop_when:
        cmd += [arg for check_id in sorted(job.stop_when.judged) for arg in ("--until-judged", check_id)]
        cmd += ["--until-first-loss"] if job.stop_when.any_loss else []
    isolation = dataclasses.replace(
        walls, memory=f"RLIMIT_AS {job.memory_limit / 2**20:.0f} MiB per process" if job.memory_limit else "none")
    # parent-death signal: the worker dies with the thread that started it (a pool thread lives as long as
    # the batch), so a SIGKILLed batch leaves no worker behind
    argv = sandbox.die_with_parent() + prefix + cmd
    env = dict(os.environ)
    env.update({BATCH_MARKER_VAR: marker, "HOME": str(scratch / "home"), "ROS_LOG_DIR": str(logs / "ros"),
                "ROS2COURSE_CONTENT": job.course,  # the worker grades on this batch's course
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
        isolation.pids_stats = dict(cgroup.stats())
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
            records.append(unfinished_result(lesson, Status.NOT_GRADABLE, f"timed out after {job.timeout:g} s",
                                       "the submission was stopped: a node that never ends or a build that hangs?"))
        elif not cancelled:
            records.append(unfinished_result(lesson, Status.GRADER_ERROR,
                                       f"the grading worker ended with exit code {popen.returncode} before grading "
                                       f"{lesson}" + (f": {tail}" if tail else ""),
                                       "see logs/worker.log; a fault of the grading machine or a limit reached"))
    order = {lesson: i for i, lesson in enumerate(job.lessons)}
    records.sort(key=lambda r: order.get(r.lesson, 0))
    isolation.killed_after = len(killed)
    return records, isolation, peak, cancelled


def _tail(path: Path, lines: int = 3) -> str:
    try:
        text = path.read_text(encoding="utf-8", errors="replace").strip().splitlines()
    except OSError:
        return ""
    return " | ".join(line.strip() for line in text[-lines:])[:400]
