"""The ``ros2course`` command line: thin wiring from arguments to ``course`` functions.

Data goes to stdout, diagnostics to stderr. Expected errors are
:class:`~ros2course.errors.CourseError`: one line plus a hint, the error's exit
code, and no traceback unless ``--debug`` (httpie's rule). The only place
that turns errors into exit codes is :func:`_handle_errors`.
"""

from __future__ import annotations

import contextlib
import functools
import os
import sys
import traceback
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Callable, Optional

import typer

from ros2course.errors import CourseError, ExitStatus

if TYPE_CHECKING:
    from rich.console import Console

    from ros2course.lesson.workspace import Workspace

# Start time (issue 13: `--help` and `list` in under 0.25 s): the catalog
# (pydantic, yaml), the ROS environment and grading are imported inside the
# commands that need them, never at module top.

app = typer.Typer(name="ros2course", no_args_is_help=True, add_completion=False, rich_markup_mode=None,
                  help="Learn ROS 2 Jazzy by writing real nodes; ros2course builds, runs and grades them.")
dev_app = typer.Typer(no_args_is_help=True, help="Course maintenance (for course authors and CI).")
app.add_typer(dev_app, name="dev")

_state = {"debug": False}

WorkspaceOpt = Annotated[Optional[Path], typer.Option(
    "--workspace", "-w", help="Workspace folder (default: nearest initialised workspace at or above the current directory).",
    file_okay=False)]


def stdout_console() -> Console:
    """Console for data (created per call, so test runners that swap sys.stdout see it)."""
    from rich.console import Console  # noqa: PLC0415 - start time, see the imports

    return Console(file=sys.stdout, highlight=False, soft_wrap=False)


def stderr_console() -> Console:
    """Console for diagnostics and progress."""
    from rich.console import Console  # noqa: PLC0415 - start time, see the imports

    return Console(file=sys.stderr, highlight=False)


def _handle_errors(func: Callable[..., Any]) -> Callable[..., Any]:
    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except CourseError as exc:
            from rich.text import Text  # noqa: PLC0415 - start time, see the imports

            err = stderr_console()
            if _state["debug"]:
                err.print(traceback.format_exc(), markup=False, highlight=False)
            # soft_wrap: one message, one line, whatever the terminal width (scripts grep it)
            err.print(Text.assemble(("error: ", "bold red"), exc.message.replace("\n", " ")), soft_wrap=True)
            if exc.hint:
                err.print(Text.assemble(("hint: ", "cyan"), exc.hint), soft_wrap=True)
            raise typer.Exit(int(exc.exit_status)) from None
        except KeyboardInterrupt:
            stderr_console().print("[yellow]interrupted[/]")
            raise typer.Exit(130) from None
    return wrapper


CourseOpt = Annotated[Optional[str], typer.Option(
    "--course", metavar="PATH|NAME", help="The course: its folder (holding course.yaml) or an installed course's name "
    "(default: the one the workspace follows, else the bundled ROS 2 tutorial).")]


def _print_version() -> None:
    """``--version``: the engine's version and grading API, and the active course's id, version and folder."""
    from importlib.metadata import PackageNotFoundError, version  # noqa: PLC0415 - start time, see the imports

    from ros2course.kit_version import API_VERSION  # noqa: PLC0415 - same
    from ros2course.lesson import active_course  # noqa: PLC0415 - same

    try:
        engine = version("ros2course")
    except PackageNotFoundError:  # running from a checkout that was never installed
        engine = "(not installed)"
    print(f"ros2course {engine} (grading API ros2course.kit {API_VERSION})")
    try:
        course = active_course()
        manifest = course.manifest()
        print(f"course {manifest.id} {manifest.version} (ROS 2 {manifest.ros_distro}) at {course.root}")
    except CourseError as exc:
        print(f"course: none ({exc.message})")


@app.callback(invoke_without_command=True)
def _root(ctx: typer.Context, debug: Annotated[bool, typer.Option("--debug", help="Show tracebacks of errors.")] = False,
          course: CourseOpt = None,
          version: Annotated[bool, typer.Option("--version", help="Print the engine's and the course's versions.")] = False,
          ) -> None:
    _state["debug"] = debug
    _state["course"] = course
    if version:
        _handle_errors(_choose_course)(None)
        _print_version()
        raise typer.Exit()
    if ctx.invoked_subcommand is None:
        typer.echo(ctx.get_help())
        raise typer.Exit()


def _choose_course(ws: Workspace | None, course: str | None = None) -> None:
    """Make the course of this command the active one (:func:`ros2course.lesson.use_course`).

    In order: ``--course`` (of the command, else the global one), ``ROS2COURSE_CONTENT``
    (taken as it is: batch workers and tests' private copies), the course the workspace
    records, the bundled tutorial. A workspace that follows
    one course is never checked against another.

    Raises:
        CourseError: the course is not found, or is not the one the workspace follows.
    """
    from ros2course.lesson import MANIFEST, use_course  # noqa: PLC0415 - start time, see the imports

    spec = course or _state.get("course")
    if spec is None and os.environ.get("ROS2COURSE_CONTENT"):
        return  # a test's or a batch worker's course folder: content_root() answers it as it is
    record = ws.course_record() if ws is not None else None
    if spec is None:
        if record is None:
            return  # the bundled tutorial course
        recorded = Path(record.get("path") or "")
        if record.get("path") and (recorded / MANIFEST).is_file() and not _extends(recorded / MANIFEST):
            use_course(recorded)  # no pydantic here: `list` stays fast
            return
        from ros2course.lesson.courses import find_course  # noqa: PLC0415 - start time, see the imports

        try:
            root = find_course(str(recorded) if record.get("path") and (recorded / MANIFEST).is_file() else record["id"])
        except CourseError as exc:
            raise CourseError(f"{ws.root} follows course {record['id']} {record.get('version', '?')}, which is not at "
                              f"{record.get('path')} any more and is not installed",
                              "pip install the package that provides it, or pass --course PATH "
                              "(your files and progress are kept)") from exc
        use_course(root)
        ws.record_course(record["id"], record.get("version", "?"), root)  # found elsewhere: remember where
        return
    from ros2course.lesson.courses import find_course, load_manifest  # noqa: PLC0415 - start time, see the imports

    root = find_course(spec)
    manifest = load_manifest(root)
    if record is not None and record["id"] != manifest.id:
        raise CourseError(f"{ws.root} follows course {record['id']} {record.get('version', '?')}, "
                          f"not {manifest.id} {manifest.version} ({root})",
                          "drop --course, or make another workspace: ros2course init --course ... DIR")
    use_course(root)


def _extends(manifest: Path) -> bool:
    """Whether a course.yaml has an ``extends:`` line (then :func:`ros2course.lesson.courses.find_course` merges
    it with the course it extends); read as text, so ``list`` of an ordinary course never loads pydantic."""
    try:
        return any(line.startswith("extends:") for line in manifest.read_text(encoding="utf-8").splitlines())
    except OSError:
        return False


def _env():
    """:mod:`ros2course.ros.env`, imported on first use (start time, see the imports)."""
    from ros2course.ros import env  # noqa: PLC0415 - start time, see the imports

    return env


def _ros() -> None:
    """Activate the ROS 2 environment in this process (:func:`ros2course.ros.env.activate`).

    Only the commands that build, run or inspect ROS call it (check, doctor,
    env, grade, gradescope, dev validate); list/show/next/hint never pay for it.
    """
    _env().activate_process()


def _workspace(workspace: Path | None) -> Workspace:
    from ros2course.lesson.workspace import find_workspace  # noqa: PLC0415 - start time, see the imports

    ws = find_workspace(explicit=workspace)
    _choose_course(ws)
    return ws


def load_catalog():
    """The course's lessons (:func:`ros2course.lesson.catalog.load_catalog`), imported on first use for start time."""
    from ros2course.lesson.catalog import load_catalog as load  # noqa: PLC0415 - start time, see the imports

    return load()


def _require_initialised(ws: Workspace) -> None:
    if not ws.initialised:
        raise CourseError(f"{ws.root} was never initialised for ros2course (no progress file)",
                          f"run 'ros2course init {ws.root}' (your files are kept)")


@app.command()
@_handle_errors
def init(directory: Annotated[Path, typer.Argument(help="Workspace folder to create.")] = Path(
        "ros2_tutorial_workspace"), course: CourseOpt = None) -> None:
    """Create a workspace (DIR/src) and its progress file, following a course (default: the bundled tutorial)."""
    if directory.exists() and not directory.is_dir():
        raise CourseError(f"{directory} exists and is not a folder", "choose another name")
    from ros2course.lesson import active_course  # noqa: PLC0415 - start time, see the imports
    from ros2course.lesson.workspace import Workspace  # noqa: PLC0415 - same

    ws = Workspace(directory)
    _choose_course(ws, course)
    chosen = active_course()
    manifest = chosen.manifest()
    created = ws.init()
    if ws.course_record() is None:
        ws.record_course(manifest.id, manifest.version, chosen.root)
    out = stdout_console()
    if created:
        out.print(f"Initialised ros2course workspace at [bold]{ws.root}[/]")
    else:
        out.print(f"{ws.root} is already a ros2course workspace; nothing changed")
    out.print(f"Next: cd {directory} && ros2course next")


@app.command("list")
@_handle_errors
def list_(workspace: WorkspaceOpt = None) -> None:
    """Every lesson, its status and best score."""
    # the kept catalog and a plain read of progress.json: no pydantic, no yaml (course/lesson/progress_view.py)
    from ros2course.lesson.catalog import load_catalog  # noqa: PLC0415 - start time, see the imports
    from ros2course.lesson.progress_view import progress_view  # noqa: PLC0415 - same
    from ros2course.report.listing import render_list  # noqa: PLC0415 - same

    ws = _workspace(workspace)  # first: it chooses the course the workspace follows
    lessons = load_catalog().lessons
    progress = progress_view(ws)
    render_list(lessons, progress, stdout_console(), root=ws.root if ws.initialised else None)
    gone = sorted(set(progress.lessons) - {lesson.id for lesson in lessons})
    if gone:  # a newer version of the course dropped them: the record stays in progress.json
        stderr_console().print(f"[yellow]note:[/] your progress file keeps {len(gone)} lesson(s) this version of the "
                               f"course no longer has: {', '.join(gone)}")


@app.command()
@_handle_errors
def show(lesson_id: Annotated[Optional[str], typer.Argument(metavar="LESSON", help="Lesson id (default: current).")] = None,
         workspace: WorkspaceOpt = None) -> None:
    """Show a lesson's instructions again (changes no file)."""
    from ros2course.report.listing import lesson_files  # noqa: PLC0415 - start time, see the imports
    from ros2course.report.table import render_lesson  # noqa: PLC0415 - start time, see the imports

    ws = _workspace(workspace)
    lesson = _lesson_for(lesson_id, ws)
    out = stdout_console()
    render_lesson(lesson, out)
    if ws.initialised:
        status = ws.load_progress().status(lesson.id)
        out.print("Your files: ", lesson_files(lesson, ws.root), f"   status: {status}", sep="")


@app.command("next")
@_handle_errors
def next_(workspace: WorkspaceOpt = None) -> None:
    """Move to the next lesson: show its instructions and copy its starter files."""
    from ros2course.lesson.starter import copy_starter  # noqa: PLC0415 - start time, see the imports
    from ros2course.report.table import render_lesson  # noqa: PLC0415 - start time, see the imports

    ws = _workspace(workspace)  # first: it chooses the course the workspace follows
    catalog = load_catalog()
    _require_initialised(ws)
    progress = ws.load_progress()
    err = stderr_console()
    if progress.current in catalog.ids() and progress.status(progress.current) != "done":
        err.print(f"[yellow]note:[/] lesson {progress.current} is not done yet; you can come back with "
                  f"'ros2course check {progress.current}'")
    if progress.current is not None and progress.current not in catalog.ids():
        err.print(f"[yellow]note:[/] your current lesson {progress.current!r} is no longer in the course; "
                  "continuing with the first lesson not done yet")
        progress.current = None
        lesson = next((item for item in catalog.lessons if progress.status(item.id) != "done"), None)
    else:
        lesson = catalog.after(progress.current)
    if lesson is None:
        stdout_console().print("You have reached the end of the course. 'ros2course list' shows your scores.")
        return
    progress.current = lesson.id
    progress.lesson(lesson.id).started = True
    copied, kept = copy_starter(lesson, ws.root)
    ws.save_progress(progress)
    out = stdout_console()
    render_lesson(lesson, out)
    for path in copied:
        out.print(f"[green]created[/] {path}")
    for path in kept:
        err.print(f"[yellow]kept your file[/] {path} (the starter version was not copied)")
    out.print("When ready: [bold]ros2course check[/]   Stuck: [bold]ros2course hint[/]")


def _lesson_for(lesson_id: str | None, ws: Workspace, progress=None):
    """The lesson named, else the workspace's current one. ``progress``: the workspace's progress, when the
    caller has read it already (read it once per command); else it is read here when needed.

    Raises:
        CourseError: no lesson named and none current. ProgressError: the progress file is unreadable.
    """
    catalog = load_catalog()
    if lesson_id:
        return catalog.get(lesson_id)
    if progress is None and ws.initialised:
        progress = ws.load_progress()
    current = progress.current if progress is not None else None
    if current is None:
        raise CourseError("no lesson given and no current lesson", "name one (ros2course list) or run 'ros2course next'")
    return catalog.get(current)


@app.command()
@_handle_errors
def check(lesson_id: Annotated[Optional[str], typer.Argument(metavar="LESSON", help="Lesson id (default: current).")] = None,
          workspace: WorkspaceOpt = None,
          as_json: Annotated[bool, typer.Option("--json", help="Print the result as JSON on stdout, nothing else.")] = False,
          all_passed: Annotated[bool, typer.Option("--all", help="Re-grade every lesson you have passed, in order, "
                                                                 "after one build, and report regressions.")] = False,
          ) -> None:
    """Build the lesson's packages, run your nodes, grade them. Exit 0 only on full marks."""
    _ros()
    ws = _workspace(workspace)
    if all_passed:
        if lesson_id:
            raise CourseError("--all re-grades every passed lesson: give no LESSON with it",
                              f"ros2course check {lesson_id}   or   ros2course check --all")
        _check_all(ws, as_json)
        return
    # read once, before the long check: a corrupt progress file is reported first (the attempt is recorded
    # on a fresh read afterwards, so one that `watch` recorded meanwhile is kept); read as `list` reads it,
    # without pydantic unless the file needs it (lesson.progress_view: issue 36)
    from ros2course.lesson.progress_view import progress_view  # noqa: PLC0415 - start time, see the imports

    progress = progress_view(ws) if ws.initialised else None
    lesson = _lesson_for(lesson_id, ws, progress)
    result = _grade(ws, lesson, quiet=as_json)
    # after grading: rich's tables are not needed before the learner's nodes start (issue 36)
    from ros2course.report.table import render_result, result_json  # noqa: PLC0415 - start time, see the imports

    if as_json:
        sys.stdout.write(result_json(result))
        sys.stdout.flush()
    else:
        render_result(result, stdout_console())
    code = _exit_status(result)
    if code:
        raise typer.Exit(int(code))


def _grade(ws: Workspace, lesson, quiet: bool = False):
    """Grade ``lesson`` in ``ws`` (building SmartArmStack first where its packages need it) and record the attempt."""
    from ros2course.grade.engine import check_lesson  # noqa: PLC0415 - start time, see the imports

    _ensure_components(ws, lesson.packages)
    status = None
    if not quiet:  # --json: no console made before the nodes start (rich's import, issue 36)
        err = stderr_console()
        status = err.status(f"grading {lesson.id} in {ws.root} ...") if err.is_terminal else None
    from ros2course.grade.deadline import check_deadline  # noqa: PLC0415 - start time, see the imports

    with status or contextlib.nullcontext(), _ctrl_c_seen() as interrupted, \
            check_deadline(f"the check of {lesson.id}", ws.root / "log" / "ros2course" / lesson.id):
        progress = (lambda line: status.update(f"{lesson.id}: {line}")) if status is not None else None
        # the learner sees the visible checks only (issue 39): the others are graded when the work is handed in
        result = check_lesson(lesson, ws.root, progress=progress)
    if interrupted:  # Ctrl+C came, and a layer below ended the check early instead of raising it
        raise KeyboardInterrupt
    if ws.initialised:
        ws.record_attempt(lesson.id, result.status.value, result.score, result.max_score)
    return result


@contextlib.contextmanager
def _ctrl_c_seen():
    """Note every SIGINT (Ctrl+C) while the block runs, and raise KeyboardInterrupt as Python does; yields the list
    of them. An interrupted check is never recorded in progress.json, whichever layer the KeyboardInterrupt
    met (a check killed mid-way loses nothing: tests/test_interrupted_check.py)."""
    import signal  # noqa: PLC0415 - start time, see the imports
    import threading  # noqa: PLC0415 - same

    seen: list[int] = []
    previous = signal.getsignal(signal.SIGINT)
    # ignored, someone else's handler, or a thread that may not set one (signal.signal: main thread only)
    if previous is not signal.default_int_handler or threading.current_thread() is not threading.main_thread():
        yield seen
        return

    def on_sigint(signum, frame) -> None:
        seen.append(signum)
        signal.default_int_handler(signum, frame)

    signal.signal(signal.SIGINT, on_sigint)
    try:
        yield seen
    finally:
        signal.signal(signal.SIGINT, previous)


def _ensure_components(ws: Workspace, packages: list[str]) -> None:
    """Build the optional components ``packages`` need first (the sas lesson's SmartArmStack: minutes, once)."""
    from ros2course.ros.doctor import ensure_components_for  # noqa: PLC0415 - start time, see the imports

    ensure_components_for(ws.root, packages,
                          progress=lambda line: stderr_console().print(f"SmartArmStack (sas): {line}", markup=False))


def _exit_status(result) -> ExitStatus:
    """The exit status of one lesson's grade: 0 only on full marks (see :class:`~ros2course.errors.ExitStatus`)."""
    from ros2course.grade.results import Status  # noqa: PLC0415 - start time, see the imports

    codes = {Status.PASSED: ExitStatus.OK, Status.NOT_GRADABLE: ExitStatus.NOT_GRADABLE,
             Status.GRADER_ERROR: ExitStatus.GRADER_ERROR}
    return codes.get(result.status, ExitStatus.CHECK_FAILED)


def _check_all(ws: Workspace, as_json: bool) -> None:
    """``check --all``: every passed lesson re-graded after one build; exit 0 only when all still pass."""
    import json  # noqa: PLC0415 - start time, see the imports

    from ros2course.grade import regrade as regrade_mod  # noqa: PLC0415 - start time, see the imports
    from ros2course.report.table import render_regrades  # noqa: PLC0415 - start time, see the imports

    _require_initialised(ws)
    catalog = load_catalog()
    progress = ws.load_progress()
    lessons = regrade_mod.passed_lessons(catalog.lessons, progress)
    if not lessons:
        if as_json:
            sys.stdout.write("[]\n")
        else:
            stdout_console().print("No lesson passed yet: nothing to re-grade. 'ros2course check' grades the current one.")
        return
    err = stderr_console()
    _ensure_components(ws, sorted({name for lesson in lessons for name in lesson.packages}))

    def shown(item) -> None:
        ws.record_attempt(item.lesson.id, item.result.status.value, item.result.score, item.result.max_score)
        if not as_json:
            verdict = "[green]still passes[/]" if not item.regression else "[bold red]REGRESSION[/]"
            err.print(f"{item.lesson.id}: {verdict} ({item.result.score:g}/{item.result.max_score:g})")

    items = regrade_mod.regrade(lessons, ws.root, progress, on_result=shown)
    if as_json:
        sys.stdout.write(json.dumps([{"lesson": i.lesson.id, "before": i.before, "regression": i.regression,
                                      **i.result.to_json()} for i in items], indent=2) + "\n")
    else:
        render_regrades(items, stdout_console())
    if any(item.regression for item in items):
        raise typer.Exit(int(ExitStatus.CHECK_FAILED))


@app.command()
@_handle_errors
def watch(workspace: WorkspaceOpt = None) -> None:
    """Re-check the current lesson whenever you save one of its files (keys: h n l c q)."""
    from ros2course.watch import Watcher  # noqa: PLC0415 - start time, see the imports

    ws = _workspace(workspace)
    _require_initialised(ws)
    raise typer.Exit(Watcher(ws, load_catalog(), stdout_console()).run())


@app.command()
@_handle_errors
def evidence(lesson_id: Annotated[Optional[str], typer.Argument(metavar="LESSON", help="Lesson id (default: current).")] = None,
             check_ids: Annotated[Optional[list[str]], typer.Argument(metavar="[CHECK]...",
                                                                      help="Check ids (default: the failed ones).")] = None,
             plot: Annotated[bool, typer.Option("--plot", help="Also draw each stream's intervals over time in the terminal, with the band the verdict allowed.")] = False,
             png: Annotated[Optional[Path], typer.Option("--png", metavar="FILE", help="Write the same plots to a PNG file (matplotlib).")] = None,
             workspace: WorkspaceOpt = None) -> None:
    """What a check saw: the recorded messages and rates of the last check of LESSON."""
    from ros2course.report import evidence as ev  # noqa: PLC0415 - start time, see the imports

    ws = _workspace(workspace)
    lesson = _lesson_for(lesson_id, ws)
    folder = ev.latest_log_dir(ws.root, lesson.id)
    out = stdout_console()
    shown = ev.render(folder, list(check_ids or []), out)
    if plot or png is not None:
        series = ev.interval_series(shown)  # the observations render read: the recording is read once
        if plot:
            ev.plot_terminal(series, out)
        if png is not None:
            ev.plot_png(series, png)
            out.print(f"wrote {png}")


@app.command()
@_handle_errors
def graph(lesson_id: Annotated[Optional[str], typer.Argument(metavar="LESSON", help="Lesson id (default: current).")] = None,
          mermaid_file: Annotated[Optional[Path], typer.Option("--mermaid", metavar="FILE",
                                                               help="Also write the comparison as a Mermaid flowchart.")] = None,
          workspace: WorkspaceOpt = None) -> None:
    """The graph LESSON's contract expects beside the one its last check observed."""
    from ros2course.report.evidence import latest_log_dir  # noqa: PLC0415 - start time, see the imports
    from ros2course.report.graph import compare, load_observed, mermaid, render  # noqa: PLC0415 - start time, see the imports

    ws = _workspace(workspace)
    lesson = _lesson_for(lesson_id, ws)
    rows = compare(lesson.graph, load_observed(latest_log_dir(ws.root, lesson.id)))
    out = stdout_console()
    render(rows, lesson.id, out)
    if lesson.graph is None:
        out.print(f"[dim]{lesson.id} declares no graph: every entry is what the check observed.[/]")
    if mermaid_file is not None:
        if mermaid_file.exists() and not mermaid_file.is_file():
            raise CourseError(f"{mermaid_file} is not a file", "give a file name, e.g. --mermaid graph.mmd")
        mermaid_file.write_text(mermaid(rows), encoding="utf-8")
        out.print(f"wrote {mermaid_file}")


@app.command()
@_handle_errors
def hint(lesson_id: Annotated[Optional[str], typer.Argument(metavar="LESSON")] = None,
         workspace: WorkspaceOpt = None) -> None:
    """Show the next hint for the lesson (each call reveals one more)."""
    ws = _workspace(workspace)
    lesson = _lesson_for(lesson_id, ws)
    progress = ws.load_progress()
    record = progress.lesson(lesson.id)
    index = min(record.hints_shown, len(lesson.hints) - 1)
    out = stdout_console()
    out.print(f"[bold cyan]Hint {index + 1}/{len(lesson.hints)}[/] for {lesson.id}:")
    from rich.markdown import Markdown  # noqa: PLC0415 - start time, see the imports

    out.print(Markdown(lesson.hints[index]))
    if record.hints_shown >= len(lesson.hints):
        out.print("[dim]That was the last hint.[/]")
    record.hints_shown = min(record.hints_shown + 1, len(lesson.hints))
    ws.save_progress(progress)


@app.command()
@_handle_errors
def reset(lesson_id: Annotated[str, typer.Argument(metavar="LESSON")],
          workspace: WorkspaceOpt = None) -> None:
    """Restore the lesson's starter files; your versions are backed up first."""
    from ros2course.lesson.starter import reset_starter  # noqa: PLC0415 - start time, see the imports

    ws = _workspace(workspace)
    lesson = load_catalog().get(lesson_id)
    backup, restored = reset_starter(lesson, ws.root, ws.state_dir / "backups")
    out = stdout_console()
    for path in restored:
        out.print(f"[green]restored[/] {path}")
    if backup is not None:
        out.print(f"Your previous files are in [bold]{backup}[/]")
    if not restored:
        out.print(f"lesson {lesson.id} has no starter files")


@app.command()
@_handle_errors
def doctor(fix: Annotated[bool, typer.Option("--fix", help="Repair the ROS wheels and build the missing ROS 2 "
                                                            "pieces (ros2 CLI, launch, rclcpp); idempotent.")] = False,
           sources: Annotated[Optional[Path], typer.Option("--sources", metavar="DIR", file_okay=False,
                                                           help="Folder of the pinned source archives (see 'env').")
                              ] = None,
           ) -> None:
    """Report what is installed (rclpy, RMW, colcon, cmake, C++, rclcpp, launch, ros2) and repair with --fix."""
    _ros()
    from rich.table import Table  # noqa: PLC0415 - start time, see the imports

    from ros2course.ros import doctor as ros_doctor  # noqa: PLC0415 - start time, see the imports

    rows = ros_doctor.doctor(fix=fix, sources=sources)
    table = Table(title="ros2course doctor", title_justify="left")
    table.add_column("component")
    table.add_column("")
    table.add_column("detail", overflow="fold")
    table.add_column("hint", overflow="fold")
    for row in rows:
        table.add_row(row.component, "[green]ok[/]" if row.ok else "[red]missing[/]", row.detail, row.hint)
    stdout_console().print(table)
    essential = {"ROS 2", "rclpy", "colcon"}
    if any(not row.ok for row in rows if row.component in essential):
        raise typer.Exit(int(ExitStatus.MISSING_REQUIREMENT))


@app.command("env")
@_handle_errors
def env_(path: Annotated[bool, typer.Option("--path", help="Print the path of the setup script to source.")] = False,
         build: Annotated[bool, typer.Option("--build", help="Build the ROS 2 underlay (ros2 CLI, launch, rclcpp) "
                                                            "unless it is up to date.")] = False,
         sources: Annotated[Optional[Path], typer.Option("--sources", metavar="DIR", file_okay=False,
                                                         help="Folder of the pinned source archives "
                                                              "(default: $ROS2COURSE_ROS_SOURCES, ../shared/ros-src "
                                                              "beside the project, else GitHub).")] = None,
         rebuild: Annotated[bool, typer.Option("--rebuild", help="With --build: build even when up to date.")] = False,
         with_: Annotated[Optional[list[str]], typer.Option("--with", metavar="COMPONENT",
                                                            help="With --build: also build an optional component "
                                                                 "(sas: SmartArmStack C++ for the sas lesson, "
                                                                 "about 6 min on 2 cores; nav2: the nav2 and Gazebo "
                                                                 "interfaces, nav2_msgs and ros_gz_interfaces, needs "
                                                                 "the nav2 extra; repeatable).")] = None,
         ) -> None:
    """The learner's ROS 2 environment: source "$(ros2course env --path)" in a terminal."""
    _ros()
    from ros2course.ros import underlay, underlay_build  # noqa: PLC0415 - start time, see the imports

    if not (path or build):
        raise CourseError("say what to do: --path or --build", 'e.g. source "$(ros2course env --path)"')
    extra = []
    for name in with_ or []:
        if name not in underlay.COMPONENTS or name == "jazzy":
            raise CourseError(f"unknown component {name!r}",
                              f"the optional components are: {', '.join(c.name for c in underlay.OPTIONAL)}")
        if underlay.COMPONENTS[name] not in extra:
            extra.append(underlay.COMPONENTS[name])
    if with_ and not build:
        raise CourseError("--with builds an optional component: it goes with --build",
                          f"e.g. ros2course env --build --with {extra[0].name}")
    if build:
        install = _env().detect()
        if install.kind == "system":
            stderr_console().print(f"a system ROS 2 {install.distro} is sourced ({install.prefix}): nothing to build")
            if underlay.NAV2_COMPONENT in extra:
                stderr_console().print(f"{underlay.NAV2_COMPONENT.what}: with a system ROS, install "
                                       f"{' '.join(underlay.NAV2_APT_PACKAGES)} (apt)", markup=False)
        else:
            err = stderr_console()
            for component in (underlay.JAZZY_COMPONENT, *extra):
                # a terminal gets a live line of the packages being built; logs and CI get the steps only
                status = err.status(f"{component.what} ...") if err.is_terminal else None
                with status or contextlib.nullcontext():
                    made, built = underlay_build.build(
                        sources, force=rebuild, component=component,
                        progress=lambda line: err.print(line, markup=False),
                        packages=(lambda line, st=status, what=component.what: st.update(f"{what}: {line}"))
                        if status is not None else None)
                state = ("up to date" if not built else
                         f"restored from the build cache in {made.stamp.get('seconds', 0):.0f} s"
                         if made.stamp.get("restored_from") else f"built in {made.stamp.get('seconds', 0):.0f} s")
                err.print(f"{component.what}: {state}: {made.prefix}", markup=False)
    if path:
        sys.stdout.write(f"{_env().write_setup_script()}\n")


@dev_app.command()
@_handle_errors
def validate(lesson_ids: Annotated[Optional[list[str]], typer.Argument(metavar="[LESSON]...")] = None,
             as_json: Annotated[bool, typer.Option("--json", help="Print the outcomes as JSON.")] = False,
             batch: Annotated[bool, typer.Option("--batch", help="Also grade each reference and a sample of wrong solutions with `ros2course grade` (the isolation this machine gives) and fail unless they get the verdicts `check` gave.")] = False,
             sample: Annotated[int, typer.Option("--sample", help="With --batch: wrong solutions per lesson handed in to the batch.")] = 2,
             repeat: Annotated[int, typer.Option("--repeat", metavar="N", help="Grade each case N times and report every check whose verdict changed (a flaky grader).")] = 0,
             load: Annotated[int, typer.Option("--load", metavar="K", help="With --repeat: K gradings at once, each on its own copy (two learners on one machine).")] = 1,
             case: Annotated[Optional[list[str]], typer.Option("--case", metavar="CASE", help="With --repeat: only this case (reference, starter or a fixture's name; repeatable).")] = None,
             jobs: Annotated[int, typer.Option("--jobs", "-j", metavar="K", help="Wrong solutions graded K at once (each in a process of its own); references and full-marks cases are always graded alone.")] = 1,
             until_settled: Annotated[bool, typer.Option("--until-settled", help="Stop grading a case once its verdict is settled: a wrong solution once the checks its fixture names are judged, the starter at its first lost point (the rest show 'not checked'; no 'also lost' notes). References are graded whole.")] = False,
             course: CourseOpt = None,
             ) -> None:
    """Grade every lesson's reference (full marks), starter (not full) and wrong solutions (named checks fail)."""
    _choose_course(None, course)
    _ros()
    from ros2course.dev.validate import render_outcomes, validate_course  # noqa: PLC0415 - start time, see the imports

    if sample < 0:
        raise CourseError(f"--sample must be 0 or more (got {sample})", "e.g. --sample 2")
    if jobs < 1:
        raise CourseError(f"--jobs must be 1 or more (got {jobs})", "e.g. --jobs 2: two wrong solutions at once")
    if repeat:
        if batch:
            raise CourseError("--repeat and --batch do not go together", "run them one after the other")
        if until_settled:
            raise CourseError("--repeat grades every check of a case: --until-settled does not go with it",
                              "drop --until-settled")
        from ros2course.dev.repeat import render_steadiness, repeat_lessons  # noqa: PLC0415 - start time

        rows = repeat_lessons(lesson_ids or None, repeat, load, case or None, progress=stderr_console())
        if as_json:
            import json  # noqa: PLC0415 - start time, see the imports

            sys.stdout.write(json.dumps([r.to_dict() for r in rows], indent=2) + "\n")
        else:
            render_steadiness(rows, stdout_console())
        if any(not r.ok for r in rows):
            raise typer.Exit(int(ExitStatus.VALIDATION_FAILED))
        return
    if batch:
        from ros2course.dev.parity import validate_with_batch  # noqa: PLC0415 - start time, see the imports

        outcomes = validate_with_batch(lesson_ids or None, sample=sample, jobs=jobs, progress=stderr_console(),
                                       until_settled=until_settled)
    else:
        outcomes = validate_course(lesson_ids or None, progress=stderr_console(), jobs=jobs, until_settled=until_settled)
    if as_json:
        import json  # noqa: PLC0415 - start time, see the imports

        sys.stdout.write(json.dumps([o.to_dict() for o in outcomes], indent=2) + "\n")
    else:
        render_outcomes(outcomes, stdout_console())
    bad = [o for o in outcomes if not o.ok]
    if bad:
        raise typer.Exit(int(ExitStatus.VALIDATION_FAILED))


@dev_app.command("contract-coverage")
@_handle_errors
def contract_coverage(write: Annotated[bool, typer.Option("--write", help="Write docs/contract-coverage.md instead of printing it.")] = False,
                      check: Annotated[bool, typer.Option("--check", help="Print nothing; fail unless docs/contract-coverage.md is up to date.")] = False,
                      course: CourseOpt = None,
                      ) -> None:
    """Every lesson's contract.yaml (issue 37) as docs/contract-coverage.md: requirements, their checks, what is not graded."""
    _choose_course(None, course)
    from ros2course.dev.coverage import coverage_doc_path, coverage_document  # noqa: PLC0415 - start time, see the imports

    text, problems = coverage_document()
    err = stderr_console()
    for problem in problems:
        sys.stderr.write(f"{problem}\n")
    path = coverage_doc_path()
    if check:
        current = path.read_text(encoding="utf-8") if path.is_file() else ""
        if current != text:
            err.print(f"{path} is not up to date: run `ros2course dev contract-coverage --write`", markup=False)
            raise typer.Exit(int(ExitStatus.VALIDATION_FAILED))
    elif write:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
        err.print(f"wrote {path}", markup=False)
    else:
        sys.stdout.write(text)
    if problems:
        raise typer.Exit(int(ExitStatus.VALIDATION_FAILED))


@dev_app.command("new-lesson")
@_handle_errors
def new_lesson(lesson_id: Annotated[str, typer.Argument(metavar="ID", help="The new lesson's id (kebab-case).")],
               course: Annotated[Path, typer.Option("--course", metavar="PATH",
                                                    help="The course folder (made, with its course.yaml, when missing).")],
               title: Annotated[Optional[str], typer.Option("--title", help="The lesson's one-line title.")] = None,
               ) -> None:
    """Scaffold a lesson (lesson.yaml, starter, grader, reference, one wrong solution) that `dev validate` passes."""
    from ros2course.dev.scaffold import new_lesson as scaffold  # noqa: PLC0415 - start time, see the imports

    written = scaffold(course, lesson_id, title)
    out = stdout_console()
    for path in written:
        out.print(f"wrote {path}")
    out.print(f"Next: ros2course dev validate {lesson_id} --course {course}")


@dev_app.command()
@_handle_errors
def mutate(lesson_ids: Annotated[list[str], typer.Argument(metavar="LESSON...", help="Lessons whose graders to test.")],
           sample: Annotated[Optional[int], typer.Option("--sample", metavar="K", help="Grade K mutants per lesson, picked with --seed (default: all).")] = None,
           seed: Annotated[int, typer.Option("--seed", metavar="S", help="Random seed of --sample.")] = 1,
           held_out: Annotated[Optional[int], typer.Option(
               "--held-out", metavar="N", help="Grade a held-out sample of N mutants instead: outside the lesson's recorded "
                                               "first sample, with the triage as it is, recorded beside it (issue 37).")] = None,
           held_out_seed: Annotated[Optional[int], typer.Option(
               "--held-out-seed", metavar="S", help="Random seed of --held-out (default: --seed + 1).")] = None,
           family: Annotated[str, typer.Option(
               "--family", metavar="TOOL", help="With --held-out: whose mutants it draws, universalmutator, "
                                                "cosmic-ray (core operators), mutmut (mutmut 2's mutations), "
                                                "poodle or mutpy (MutPy's operators; the last four: Python files "
                                                "only).")] = "universalmutator",
           jobs: Annotated[int, typer.Option("--jobs", "-j", help="Mutants graded at once.")] = 1,
           out: Annotated[Path, typer.Option("--out", "-o", metavar="DIR", help="Cache, batch outputs, mutation.json and survivors' diffs.")] = Path("mutation-out"),
           timeout: Annotated[float, typer.Option("--timeout", help="Wall-clock limit per mutant, seconds.")] = 300.0,
           first_loss: Annotated[bool, typer.Option(
               "--first-loss", help="Stop grading each mutant at its first lost point: the same killed/survived "
                                    "outcomes, sooner; a killed mutant's lost checks are those before the stop.")] = False,
           as_json: Annotated[bool, typer.Option("--json", help="Print the results as JSON instead of the table.")] = False,
           course: CourseOpt = None,
           ) -> None:
    """Grade mutants of each lesson's reference (universalmutator; cosmic-ray or mutmut for a held-out sample) with its grader:
    killed, survived, score."""
    _choose_course(None, course)
    _ros()
    from ros2course.dev.mutate import as_dicts, mutate_lessons, render  # noqa: PLC0415 - start time, see the imports

    if timeout <= 0:
        raise CourseError(f"--timeout must be positive (got {timeout:g})", "e.g. --timeout 300")
    if held_out is not None and held_out < 1:
        raise CourseError(f"--held-out must be at least 1 (got {held_out})", "e.g. --held-out 30")
    found = mutate_lessons(lesson_ids, out, sample=sample, seed=seed, jobs=jobs, timeout=timeout,
                           console=stderr_console(), held_out=held_out, held_out_seed=held_out_seed,
                           first_loss=first_loss, family=family)
    if as_json:
        import json  # noqa: PLC0415 - start time, see the imports

        sys.stdout.write(json.dumps(as_dicts(found), indent=2) + "\n")
    else:
        render(found, stdout_console())
    stderr_console().print(f"results: {out.absolute() / 'mutation.json'}")


@app.command()
@_handle_errors
def grade(submissions: Annotated[Path, typer.Argument(metavar="SUBMISSIONS",
                                                      help="Folder with one entry per student: a workspace, a folder of packages, or a .zip / .tar.gz of either "
                                                           "(--from: an LMS download or a folder of git clones).")],
          lesson: Annotated[list[str], typer.Option("--lesson", "-l", metavar="LESSON", help="Lesson to grade (repeatable).")],
          out: Annotated[Path, typer.Option("--out", "-o", metavar="OUTDIR", help="Where the gradebook and results go.")],
          jobs: Annotated[Optional[int], typer.Option("--jobs", "-j", help="Submissions graded at once (default: number of cores).")] = None,
          timeout: Annotated[float, typer.Option("--timeout", help="Wall-clock limit per submission, seconds.")] = 300.0,
          scheduler: Annotated[Optional[str], typer.Option("--scheduler", envvar="DASK_SCHEDULER_ADDRESS",
                                                           help="Dask scheduler address: grade on that cluster instead.")] = None,
          resume: Annotated[bool, typer.Option("--resume", help="Skip submissions already in OUTDIR/results.jsonl.")] = False,
          regrade: Annotated[Optional[str], typer.Option("--regrade", metavar="changed|all",
                                                         help="Regrade the rows of OUTDIR whose grader or submission changed since (changed), or every row (all).")] = None,
          only: Annotated[Optional[list[str]], typer.Option("--only", metavar="STUDENT",
                                                            help="Grade (or regrade: an appeal) only this student's submission (repeatable).")] = None,
          memory_mb: Annotated[int, typer.Option("--memory-mb", help="Address-space limit per process of a submission, MiB (0: none).")] = 4096,
          pids_limit: Annotated[int, typer.Option("--pids-limit", help="Processes + threads a submission may have at once.")] = 256,
          require_isolation: Annotated[bool, typer.Option("--require-isolation",
                                                          help="Refuse to grade unless every protection (namespaces, unprivileged uid, process limit) is in effect.")] = False,
          no_report: Annotated[bool, typer.Option("--no-report", help="Do not write OUTDIR/report.html at the end.")] = False,
          from_fmt: Annotated[str, typer.Option("--from", metavar="folder|canvas|moodle|blackboard|git",
                                                help="What SUBMISSIONS is: today's folder, an LMS's download of all submissions (a .zip or its "
                                                     "unpacked folder), or a folder of git clones; taken into OUTDIR/intake/ first.")] = "folder",
          before: Annotated[Optional[str], typer.Option("--before", metavar="DATETIME",
                                                        help="Deadline, ISO 8601 with its time zone (2026-03-01T23:59:00+01:00): "
                                                             "--from git takes each clone's last commit before it.")] = None,
          course: CourseOpt = None,
          ) -> None:
    """Grade a whole class: each submission isolated, in parallel, resumable; writes a gradebook."""
    from ros2course.batch import intake as intake_mod  # noqa: PLC0415 - start time, see the imports

    if from_fmt not in intake_mod.FORMATS:
        raise CourseError(f"unknown --from {from_fmt!r}", f"use --from {', --from '.join(intake_mod.FORMATS)}")
    deadline = intake_mod.parse_deadline(before) if before is not None else None
    _choose_course(None, course)
    _ros()
    from ros2course.batch.runner import render_summary, run_batch  # noqa: PLC0415 - start time, see the imports

    err = stderr_console()
    if memory_mb < 0:
        raise CourseError(f"--memory-mb must be 0 or more (got {memory_mb})", "e.g. --memory-mb 4096")
    not_taken: dict[str, str] | None = None
    if from_fmt != "folder":  # issue 39: the LMS download or the clones become OUTDIR/intake/, graded as today
        if (out / "results.jsonl").is_file() and not (resume or regrade or only):  # before the intake replaces its folder
            raise CourseError(f"{out} already holds results (results.jsonl)",
                              "add --resume to continue that batch, --regrade changed to regrade what changed, "
                              "or choose another --out folder")
        taken = intake_mod.intake(submissions, from_fmt, out / "intake", before=deadline)
        err.print(f"intake ({from_fmt}): {len(taken.taken)} submissions in {taken.folder}, "
                  f"{len(taken.problems)} not taken (see {taken.staging / intake_mod.MANIFEST})")
        for student, why in taken.problems.items():
            err.print(f"  not taken: {student}: {why}", markup=False, highlight=False)
        submissions, not_taken = taken.folder, taken.problems
    report = run_batch(submissions, lesson, out, jobs=jobs, timeout=timeout, scheduler=scheduler, resume=resume,
                       console=err, memory_limit=memory_mb * 1024 * 1024, pids_limit=pids_limit,
                       require_isolation=require_isolation, regrade=regrade, only=only,
                       not_taken=not_taken)
    if from_fmt == "folder":  # the manifest of today's layout (cheap: nothing copied); never fails a batch
        try:
            intake_mod.intake(submissions, "folder", out / "intake")
        except CourseError as exc:
            err.print(f"warning: {out / 'intake'} was not written: {exc.message}", markup=False, highlight=False)
    render_summary(report, err)
    stdout_console().print(f"gradebook: {report.out_dir / 'gradebook.csv'}")
    if not no_report:
        try:
            from ros2course.report.html import write_report  # noqa: PLC0415 - start time, see the imports

            stdout_console().print(f"report: {write_report(report.out_dir, submissions=submissions)}")
        except Exception as exc:  # noqa: BLE001 - the report never changes grade's exit status
            err.print(f"warning: the report was not written: {exc}")


@app.command()
@_handle_errors
def report(out_dir: Annotated[Path, typer.Argument(metavar="OUTDIR", help="The --out folder of `ros2course grade`.")],
           fmt: Annotated[str, typer.Option("--format", help="html (writes OUTDIR/report.html) or md (prints a summary).")] = "html",
           no_similarity: Annotated[bool, typer.Option("--no-similarity", help="Do not compare the submissions.")] = False,
           submissions: Annotated[Optional[Path], typer.Option("--submissions", metavar="SUBMISSIONS",
                                                               help="The submissions folder graded: similar submissions are looked for in it.")] = None,
           exclude_reference: Annotated[bool, typer.Option("--exclude-reference/--no-exclude-reference",
                                                           help="Leave the reference solution's code out of the similarity (the starter always is).")] = True,
           ) -> None:
    """The instructor's view of a graded class: a self-contained HTML report (or a Markdown summary)."""
    from ros2course.report.html import write_markdown, write_report  # noqa: PLC0415 - start time, see the imports

    if fmt not in ("html", "md"):
        raise CourseError(f"unknown --format {fmt!r}", "use --format html or --format md")
    if fmt == "md":
        sys.stdout.write(write_markdown(out_dir))
        return
    if submissions is not None and not submissions.is_dir():
        raise CourseError(f"--submissions {submissions} is not a folder", "give the folder graded by `ros2course grade`")
    stdout_console().print(str(write_report(out_dir, similarity=not no_similarity, submissions=submissions,
                                            exclude_reference=exclude_reference)))


@app.command("export")
@_handle_errors
def export_(out_dir: Annotated[Path, typer.Argument(metavar="OUTDIR", help="The --out folder of `ros2course grade`.")],
            fmt: Annotated[str, typer.Option("--format", help="canvas (Gradebook import CSV), moodle (grade import CSV) "
                                             "or csv (every adjustment with its reason).")] = "csv",
            class_path: Annotated[Optional[Path], typer.Option("--class", metavar="CLASS_YAML",
                                                               help="The class file: due dates, extensions, late policy "
                                                               "(default: OUTDIR/class.yaml when it exists).")] = None,
            output: Annotated[Optional[Path], typer.Option("--output", "-o", metavar="FILE",
                                                           help="Write here instead of stdout.")] = None,
            course: CourseOpt = None,
            ) -> None:
    """Export the class's gradebook, late penalties applied, for Canvas, Moodle or as a CSV."""
    _choose_course(None, course)
    from ros2course.files import atomic_write_text  # noqa: PLC0415 - start time, see the imports
    from ros2course.report.lms import FORMATS, export  # noqa: PLC0415 - same
    from ros2course.report.term import adjust_out_dir, intake_format  # noqa: PLC0415 - same

    if fmt not in FORMATS:
        raise CourseError(f"unknown --format {fmt!r}", "use --format canvas, --format moodle or --format csv")
    if output is not None and output.is_dir():
        raise CourseError(f"--output {output} is a folder", "give a file name, e.g. --output grades-canvas.csv")
    book = adjust_out_dir(out_dir, class_path)
    text = export(book.adjusted, fmt, book.names, book.lessons, canvas_user_ids=intake_format(out_dir) == "canvas")
    if output is None:
        sys.stdout.write(text)
        return
    try:
        atomic_write_text(output, text)
    except OSError as exc:
        raise CourseError(f"cannot write {output}: {exc.strerror or exc}", "check that its folder exists and is writable") from None
    late = sum(1 for row in book.adjusted if row.late)
    stderr_console().print(f"{len(book.adjusted)} result(s), {late} late"
                           + (f" (class file {book.class_path})" if book.class_path else " (no class file: nothing adjusted)"),
                           markup=False, highlight=False)
    stdout_console().print(str(output), markup=False, highlight=False)


@app.command()
@_handle_errors
def gradescope(lesson: Annotated[Optional[list[str]], typer.Option("--lesson", "-l", metavar="LESSON",
                                                                   help="Lesson(s) to grade (default: $ROS2COURSE_LESSON or the file gradescope/lesson).")] = None,
               submission: Annotated[Path, typer.Option("--submission", help="The student's upload.")] = Path("/autograder/submission"),
               results: Annotated[Path, typer.Option("--results", help="Where Gradescope reads the result.")] = Path(
                   "/autograder/results/results.json"),
               timeout: Annotated[float, typer.Option("--timeout", help="Wall-clock limit, seconds.")] = 600.0,
               pids_limit: Annotated[int, typer.Option("--pids-limit", help="Processes + threads the submission may have at once.")] = 256,
               require_isolation: Annotated[bool, typer.Option("--require-isolation",
                                                               help="Refuse to grade unless every protection is in effect.")] = False,
               ) -> None:
    """Grade one submission inside a Gradescope autograder container (writes results.json)."""
    _choose_course(None)
    _ros()
    from ros2course.batch.gradescope import run_gradescope  # noqa: PLC0415 - start time, see the imports

    score = run_gradescope(lesson or [], submission, results, timeout=timeout, pids_limit=pids_limit,
                           require_isolation=require_isolation)
    stdout_console().print(f"score {score:g}; results in {results}")


def main() -> None:
    """Console-script entry point: the one place that exits the process."""
    os.environ.setdefault("RCUTILS_COLORIZED_OUTPUT", "0")
    try:
        app()
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    if "rclpy" in sys.modules:
        # Every ROS context was shut down and every learner process stopped by now, but the
        # interpreter's own teardown of rclpy / Fast DDS takes 0.2-0.4 s more (measured in
        # benchmarks/check_speed.py); skip it once our output is flushed.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    main()
