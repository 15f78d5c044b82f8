"""The grading engine: build, launch, observe, judge, tear down.

A grader module (``graders/<name>.py``) declares ``CHECKS`` (a list of
:class:`~ros2course.grade.checklist.Check`) and a function
``grade(session: GradingSession) -> None`` that composes probes and calls
:meth:`~ros2course.grade.session.GradingSession.record` for each check.
:func:`grade_lesson` builds the lesson's packages, loads the grader (:func:`load_grader`)
and always produces a :class:`LessonResult`, even when the grader itself crashes
(otter-grader's rule): a visible "grader error" for the learner, the traceback in the log
for the instructor.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import hashlib
import importlib
import importlib.util
import json
import sys
import time
import traceback
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ros2course.builder import colcon as build_mod
from ros2course.builder.reference import lesson_dependencies
from ros2course.errors import CourseError, NotGradable
from ros2course.grade.results import LessonResult, Status
from ros2course.lesson.catalog import Lesson, content_root
from ros2course.ros import env as env_mod
from ros2course.run.process import sweep_stale_fastdds_shm



from ros2course.grade.checklist import STOPPED_SETTLED, Check, StopWhen, VerdictSettled
from ros2course.grade.session import GradingSession


def graders_package(course_root: Path | None = None) -> str:
    """Import a course's ``graders/`` folder as a package of its own; return the package's name.

    Each course folder gets a name derived from its resolved path
    (``_ros2course_graders_<hash>``), so two courses loaded in one process never
    see each other's graders, and graders are never looked up by a global name
    such as ``graders.<name>`` on ``sys.path`` (issue 18). Inside a course's
    graders, ``from . import other_grader`` reaches a sibling module; the kit is
    imported from the engine (``from ros2course import kit``).

    Args:
        course_root: the course folder (default: :func:`content_root`, the active course).

    Raises:
        CourseError: the course has no ``graders/`` folder.
    """
    folder = ((course_root or content_root()) / "graders").resolve()
    name = "_ros2course_graders_" + hashlib.sha256(str(folder).encode()).hexdigest()[:12]
    if name in sys.modules:
        return name
    init = folder / "__init__.py"
    if not folder.is_dir():
        raise CourseError(f"the course at {folder.parent} has no graders/ folder",
                          "a course folder holds course.yaml, chapters/, graders/ and solutions/")
    spec = importlib.util.spec_from_file_location(name, init if init.is_file() else None,
                                                  submodule_search_locations=[str(folder)])
    if spec is None:  # pragma: no cover - only for a folder importlib cannot describe
        raise CourseError(f"cannot import the graders of {folder}", "check the folder's permissions")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        if spec.loader is not None:
            spec.loader.exec_module(module)
    except BaseException:
        sys.modules.pop(name, None)
        raise
    return name


def load_grader(name: str, course_root: Path | None = None):
    """Import the grader module ``<course>/graders/<name>.py``; it must define ``CHECKS`` and ``grade``.

    Args:
        name: the lesson's ``grader:`` field (a module name).
        course_root: the course folder (default: the active course, :func:`content_root`).

    Raises:
        CourseError: the module is missing, fails to import or is incomplete.
    """
    package = graders_package(course_root)
    try:
        module = importlib.import_module(f"{package}.{name}")
    except ImportError as exc:
        raise CourseError(f"grader module graders/{name}.py cannot be imported: {exc}",
                          "check the lesson's 'grader:' field") from exc
    if not hasattr(module, "CHECKS") or not hasattr(module, "grade"):
        raise CourseError(f"grader module graders/{name}.py lacks CHECKS or grade()",
                          "a grader declares CHECKS and defines grade(session); see graders/README.md")
    return module


def new_log_dir(workspace_root: Path, lesson_id: str) -> Path:
    """A fresh ``log/ros2course/<lesson>/<timestamp>`` folder; ``latest`` points at it."""
    stamp = dt.datetime.now().strftime("%Y-%m-%d_%H-%M-%S-%f")
    folder = workspace_root / "log" / "ros2course" / lesson_id / stamp
    folder.mkdir(parents=True, exist_ok=True)
    latest = folder.parent / "latest"
    with contextlib.suppress(OSError):
        if latest.is_symlink() or latest.exists():
            latest.unlink()
        latest.symlink_to(folder.name)
    return folder


def grade_lesson(lesson: Lesson, workspace_root: Path, log_dir: Path | None = None,
                 underlays: tuple[Path, ...] | list[Path] = (), trusted_interfaces: Path | None = None,
                 progress: Any = None, build_also: Sequence[str] | None = None, hand_in: bool = False,
                 stop_when: StopWhen | None = None) -> LessonResult:
    """Build the lesson's packages in ``workspace_root``, run its grader, return the result.

    ``underlays`` are built workspaces sourced before building and running the
    submission (ROS's overlay mechanism), e.g. reference interface packages an
    instructor built once for a whole class. ``trusted_interfaces`` is a built
    workspace of the course's own interface packages: when given, the grader
    imports message types from it instead of from the submission (batch
    grading: generated code is code the submission controls).

    ``progress(line)``, when given, hears what colcon is building (see
    :class:`~ros2course.ros.colcon_log.BuildProgress`).

    ``build_also`` names packages built too when the workspace holds them: by default the
    course's reference dependencies of the lesson's packages
    (:func:`~ros2course.builder.reference.lesson_dependencies`, read from ``solutions/``); batch
    grading passes them in, since its worker cannot see ``solutions/``.

    ``hand_in`` (batch grading): the workspace is a submission unpacked by ``grade``, whose
    build the engine never trusts (:func:`ros2course.batch.archive.prepare` drops its build
    record, so its packages are built from clean); the build check says so.

    ``stop_when`` (``dev validate --until-settled``, never a learner's or a class's grading): grading
    stops once the verdicts recorded settle the case (:class:`~ros2course.grade.checklist.StopWhen`); the
    checks left show "not checked: " + :data:`~ros2course.grade.checklist.STOPPED_SETTLED`.

    Never raises for problems of the submission (they become the result);
    raises :class:`~ros2course.errors.MissingRequirement` when the machine lacks
    what the lesson ``requires`` (so a missing rclcpp is never a pass).
    """
    env_mod.require(lesson.requires, f"lesson {lesson.id}")
    sweep_stale_fastdds_shm()  # leftovers of an earlier run that was SIGKILLed
    module = load_grader(lesson.grader, lesson.course.root)
    checks: list[Check] = list(module.CHECKS)
    max_score = float(sum(c.points for c in checks))
    log_dir = log_dir or new_log_dir(workspace_root, lesson.id)
    base_env = env_mod.activate()
    for underlay in underlays:
        base_env = build_mod.overlay_env(Path(underlay), base_env)
    timings: dict[str, float] = {}
    build_info: dict[str, Any] = {}
    sources_digest = ""

    def not_gradable(message: str, hint: str) -> LessonResult:
        return LessonResult(lesson.id, 0.0, max_score, Status.NOT_GRADABLE, [], message, hint, timings,
                            build_info, str(log_dir))

    if lesson.packages:
        try:
            built = _build(lesson, workspace_root, base_env, log_dir, progress, build_also, trusted_interfaces)
            if built.prebuilt and trusted_interfaces is not None:  # the learner's nodes run against that install
                base_env = build_mod.overlay_env(Path(trusted_interfaces), base_env)
        except NotGradable as exc:
            return not_gradable(exc.message, exc.hint)
        timings["build"] = built.seconds
        sources_digest = built.content_digest
        build_info = {"ok": built.ok, "cached": built.cached, "seconds": round(built.seconds, 3),
                      "log": str(built.log_path) if built.log_path else "", "repairs": built.repairs,
                      **({"prebuilt": built.prebuilt} if built.prebuilt else {})}
        if not built.ok:
            return not_gradable(f"colcon build failed for {', '.join(lesson.packages)}:\n{built.excerpt}",
                                f"fix the build error; full log: {built.log_path}")
    session = GradingSession(lesson, checks, workspace_root, log_dir, base_env, trusted_interfaces, sources_digest,
                             stop_when)
    if lesson.packages and "build" in session.checks:
        session.record("build", True, "colcon built " + ", ".join(lesson.packages)
                       + (" from clean, as every hand-in is (a build the submission brought is never used)"
                          if hand_in else "")
                       + (" (unchanged since the last build)" if build_info.get("cached") else "")
                       + "".join(f"; {repair}" for repair in build_info.get("repairs", [])),
                       "the package builds with colcon")
    try:
        status, message, hint = _run_grader(module, session, timings)
    except NotGradable as exc:
        return not_gradable(exc.message, exc.hint)
    results = session.ordered_results()
    score = round(sum(r.points for r in results), 3)
    if status is None:
        status = Status.PASSED if score >= max_score else Status.FAILED
    result = LessonResult(lesson.id, score, max_score, status, results, message, hint, timings, build_info,
                          str(log_dir), session.plots)
    with contextlib.suppress(OSError):
        (log_dir / "result.json").write_text(json.dumps(result.to_json(), indent=2), encoding="utf-8")
    return result


def check_lesson(lesson: Lesson, workspace_root: Path, progress: Any = None) -> LessonResult:
    """A learner's own ``ros2course check`` (and ``check --all``'s regrade): :func:`grade_lesson` of the
    workspace, shown as the learner may see it (:meth:`~ros2course.grade.results.LessonResult.for_learner`:
    the visible checks only, and how many more are graded at hand-in; issue 39). ``progress`` as for
    :func:`grade_lesson`. Raises what :func:`grade_lesson` raises."""
    return grade_lesson(lesson, workspace_root, progress=progress).for_learner()


def _build(lesson: Lesson, workspace_root: Path, base_env: dict[str, str], log_dir: Path, progress: Any,
           build_also: Sequence[str] | None, trusted_interfaces: Path | None = None) -> build_mod.BuildResult:
    """:func:`grade_lesson`'s colcon build of the lesson's packages (``log_dir/build.log``).

    The lesson's interfaces and the earlier lessons' packages its reference depends on are built
    too when ``src/`` holds them: a package.xml that forgets a ``<depend>`` then loses only the
    check on its dependencies, in a fresh hand-in (``grade``) as in a learner's workspace built
    lesson by lesson.

    With ``trusted_interfaces`` (batch grading), a package of an earlier lesson that the hand-in holds
    unchanged from the course's copy is not built again: the course's build of it is used
    (:func:`ros2course.builder.colcon.build_packages`' ``prebuilt``); the lesson's own packages always are.

    Raises:
        NotGradable: colcon could not be run on the workspace.
    """
    also = [*lesson.interfaces, *(lesson_dependencies(lesson) if build_also is None else build_also)]
    built = build_mod.build_packages(workspace_root, lesson.packages, base_env, log_dir / "build.log",
                                     progress=progress, also=also,
                                     prebuilt=Path(trusted_interfaces) if trusted_interfaces else None)
    if progress is not None:
        for repair in built.repairs:
            progress(f"repaired the build: {repair}")
        progress("running and grading your nodes ...")
    return built


def _run_grader(module: Any, session: GradingSession, timings: dict[str, float]) -> tuple[Status | None, str, str]:
    """Run the grader's ``grade(session)``, then close the session; fill ``timings`` (seconds).

    Returns:
        ``(None, "", "")`` when the grader ran to its end (the checks decide), or
        ``(Status.GRADER_ERROR, message, hint)`` when it crashed (traceback in ``grader-error.txt``).

    Raises:
        NotGradable: the grader found the submission cannot be graded.
    """
    begin = time.monotonic()
    try:
        try:
            with session.part():  # Unmet in grade(): the unrecorded checks become "not checked" with its reason
                module.grade(session)
                # a grader whose last step was the verdict that settled a --until-settled case takes no next
                # step to notice: the checks it left (e.g. the ones Session.wanted skipped) are unjudged too
                session.book.stop_if_settled()
        finally:
            graded = time.monotonic()
            timings["grade"] = graded - begin
            session.close()
            timings["teardown"] = time.monotonic() - graded
            timings.update(session.timings)
    except NotGradable:
        raise
    except VerdictSettled:  # dev validate --until-settled: nothing after this can change the case's verdict
        session.leave_unjudged(STOPPED_SETTLED)
    except Exception as exc:  # noqa: BLE001 - any grader crash becomes a visible "grader error"
        trace_file = session.log_dir / "grader-error.txt"
        trace_file.write_text(traceback.format_exc(), encoding="utf-8")
        return (Status.GRADER_ERROR, f"the grader failed: {type(exc).__name__}: {exc}",
                f"this is a fault of the course, not of your code; traceback in {trace_file}")
    return None, "", ""
