"""The object a grader is handed: :class:`GradingSession`, three parts composed behind one door.

The verdict book (:mod:`ros2course.grade.verdicts`: verdicts, needs, parts, closing actions), the
observer (:mod:`ros2course.grade.observer`: the check's ROS graphs, recording, graph snapshots and
diagnoses) and the machine view (:mod:`ros2course.grade.machine`: the sourced workspace, the ament
index, interface types, the processes started as the submission). A grader sees the members of
:class:`ros2course.kit.Session` (``tests/test_session_protocol.py`` keeps it so); the public grading
module :mod:`ros2course.kit` re-exports the class; :func:`ros2course.grade.engine.grade_lesson` creates
one per check. The session itself keeps what belongs to the report: timings, plots, notes, and the
submission's random draws.
"""

from __future__ import annotations

import contextlib
import hashlib
import random
import subprocess
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from ros2course.builder.sources import scan_package
from ros2course.errors import NotGradable
from ros2course.grade.machine import MachineView
from ros2course.grade.results import CheckResult, Plot
from ros2course.grade.verdicts import Band, VerdictBook
from ros2course.lesson.catalog import Lesson
from ros2course.grade.checklist import Check, StopWhen
from ros2course.grade.observer import Observer
from ros2course.run.process import LearnerProcess

__all__ = ["Band", "GradingSession"]


class GradingSession:
    """What a grader's ``grade()`` works with: a verdict book, an observer and a machine view, composed.

    * the verdict book (:class:`~ros2course.grade.verdicts.VerdictBook`, :attr:`book`): verdicts, needs,
      parts and their closing actions, settling a ``dev validate --until-settled`` case;
    * the observer (:class:`~ros2course.grade.observer.Observer`, :attr:`observer`): the check's private
      ROS graphs (:attr:`ros`, :attr:`graph`, :meth:`new_graph`), its MCAP recording, the graph snapshots
      and diagnoses of failed checks;
    * the machine view (:class:`~ros2course.grade.machine.MachineView`, :attr:`machine`): the sourced
      workspace, the ament index, interface types, and the processes started as the submission.

    The session itself keeps timings, plots and notes (the report's) and the submission's random draws.
    A grader sees the members :class:`ros2course.kit.Session` lists; the rest is the engine's.

    Attributes:
        lesson: the :class:`~ros2course.lesson.catalog.Lesson`.
        workspace_root: the colcon workspace being graded.
        log_dir: this check's log folder (node stdout/stderr go here).
        base_env: the ROS install's environment (no workspace overlay).
        book: the verdict book; :attr:`results`, :attr:`checks`, :attr:`windows` and :attr:`bands` are its.
        observer: the observer; :attr:`recorder`, :attr:`graph_snapshots` and :attr:`diagnose_seconds` are its.
        machine: the machine view.

    ``stop_when`` (``dev validate --until-settled`` only): grading stops at the grader's next step once
    the verdicts recorded settle the case (:meth:`~ros2course.grade.verdicts.VerdictBook.stop_if_settled`);
    None for every real grading.

    Raises:
        CourseError: (constructing) a check needs an unknown or later check.
    """

    def __init__(self, lesson: Lesson, checks: list[Check], workspace_root: Path, log_dir: Path,
                 base_env: dict[str, str], trusted_interfaces: Path | None = None, sources_digest: str = "",
                 stop_when: StopWhen | None = None) -> None:
        self.lesson = lesson
        self.book = VerdictBook(checks, stop_when)
        self.machine = MachineView(lesson, workspace_root, log_dir, base_env, trusted_interfaces)
        self.observer = Observer(lesson, log_dir, self.book.stop_if_settled, self.phase)
        # the build's digest of the lesson's package contents (BuildResult.content_digest): seeds :attr:`random`
        self._sources_digest = sources_digest
        self._timings_lock = threading.Lock()
        self.workspace_root = workspace_root
        self.log_dir = log_dir
        self.base_env = base_env
        self.trusted_interfaces = trusted_interfaces
        self.notes: list[str] = []
        #: seconds per named phase (``start``, ``observe``, ``stop``...), see :meth:`phase`.
        self.timings: dict[str, float] = {}
        #: time series to show under the table of checks, see :meth:`add_plot`.
        self.plots: list[Plot] = []
        self._random: random.Random | None = None

    # --- the verdict book's, as graders and the engine name them ------------------------------------

    @property
    def checks(self) -> dict[str, Check]:
        """``{check id: Check}`` of the grader's ``CHECKS`` (the verdict book's)."""
        return self.book.checks

    @property
    def results(self) -> dict[str, CheckResult]:
        """Verdicts so far, ``{check id: CheckResult}`` (the verdict book's; write through :meth:`record`)."""
        return self.book.results

    @property
    def windows(self) -> dict[str, tuple[int, int]]:
        """``{check id: (start_ns, end_ns)}``: the wall-clock window each verdict judged (see :meth:`record`)."""
        return self.book.windows

    @property
    def bands(self) -> dict[str, Band]:
        """``{check id: Band}``: the seconds between events a verdict allowed and the statistic it bounded."""
        return self.book.bands

    def record(self, check_id: str, passed: bool, observed: str, expected: str, hint: str | None = None,
               fraction: float | None = None, window: tuple[float, float] | None = None,
               band: tuple[float, float] | None = None, band_of: str = "mean") -> bool:
        """Record the verdict on ``check_id``; returns ``passed``.

        A failed verdict may get the engine's diagnosis of the graph (:meth:`~ros2course.grade.observer.Observer.diagnosis`);
        it never changes the verdict or the points. The verdict book writes it
        (:meth:`~ros2course.grade.verdicts.VerdictBook.record`: a check whose needs failed is "not checked").

        Args:
            observed: what the grader saw, in the learner's terms.
            expected: what the lesson's contract asks for.
            hint: overrides the check's default hint (shown only on failure).
            fraction: partial credit in [0, 1] (default: all or nothing).
            window: the wall-clock span the verdict judged (``time.time()`` seconds: first and last
                send stamp of a rate); default: from the previous verdict of this thread (or the
                start of its part) to now. Kept with the check's recording (:mod:`ros2course.run.recording`).
            band: the interval between events the verdict allowed, ``(low, high)`` seconds (a rate's
                mean period ± its tolerance), kept with the window for ``ros2course evidence --plot``.
            band_of: the statistic of the intervals the band was applied to: ``"mean"`` or ``"median"``.

        Raises:
            KeyError: ``check_id`` is not declared in the grader's ``CHECKS``.
        """
        return self.book.record(check_id, passed, observed, expected, hint, fraction, window, band, band_of,
                                on_verdict=self.observer.on_verdict)

    def amend(self, check_id: str, *, observed: str | None = None, hint: str | None = None) -> None:
        """Add to a recorded verdict's explanation; its points and pass/fail stay.

        Args:
            observed: replaces the observed text (e.g. the first text plus what else was found).
            hint: replaces the hint.

        Raises:
            KeyError: ``check_id`` has no verdict yet.
        """
        self.book.amend(check_id, observed=observed, hint=hint)

    def unmet_need(self, check_id: str) -> str | None:
        """Why ``check_id`` cannot be judged: a sentence naming the first of its needs that did not pass.

        None while every need passed or is still to be judged. Needs are
        followed through: a need that was itself not checked blocks too.
        """
        return self.book.unmet_need(check_id)

    def require(self, *check_ids: str) -> None:
        """Go on only if every check in ``check_ids`` passed.

        Raises:
            Unmet: one of them failed or is not recorded; the current :meth:`part` ends.
        """
        self.book.require(*check_ids)

    @contextlib.contextmanager
    def part(self, name: str = "", *, own_graph: bool = False) -> Iterator[None]:
        """Grade one independent part of a lesson (e.g. one of two executables).

        :class:`Unmet` raised inside ends only this part. On the way out the
        part's closing actions (:meth:`on_close`, e.g. judging Ctrl+C of a
        node it started) run, newest first, whatever happened
        (:meth:`~ros2course.grade.verdicts.VerdictBook.part`).

        Args:
            name: the part's name (feedback, ``graph.json``).
            own_graph: the part gets a private graph of its own (:meth:`new_graph`);
                :attr:`graph`, and so every kit step and :meth:`launch` inside it,
                use that graph without a ``graph=`` argument.
        """
        self.book.stop_if_settled()
        self.observer.open_part(name, own_graph=own_graph)
        try:
            with self.book.part(name):
                yield
        finally:
            self.observer.close_part()

    def wanted(self, check_id: str) -> bool:
        """Whether ``check_id``'s verdict can still matter (:meth:`~ros2course.grade.verdicts.VerdictBook.wanted`)."""
        return self.book.wanted(check_id)

    def leave_unjudged(self, reason: str) -> None:
        """Record every check not recorded yet as not checked because of ``reason``, whatever its needs: the
        end of a grading stopped early (``dev validate --until-settled``), where no check after the stop was judged.
        """
        self.book.leave_unjudged(reason)

    def on_close(self, action: Any) -> None:
        """Run ``action()`` when the current :meth:`part` (or ``grade()``) ends, even after :class:`Unmet`."""
        self.book.on_close(action)

    def ordered_results(self) -> list[CheckResult]:
        """Every declared check's result, in declaration order; unrecorded ones become "not checked".

        A failed verdict carries its ``evidence`` (the recording and the window it judged).
        """
        recorder = self.observer.recorder
        return self.book.ordered(str(recorder.path) if recorder is not None else None)

    # --- the observer -------------------------------------------------------------------------------

    @property
    def random(self) -> random.Random:
        """The grader's random draws for this submission (a goal's direction, a value to send).

        Seeded from the lesson id and the content of the lesson's packages as the build read them
        (``sources_digest``), or of the whole ``src/`` for a lesson without packages (each file's path and
        bytes; never times or permission bits, which a copy or a hand-in changes): the same files get
        the same probes, through ``check`` and through ``grade``, run after run, so a partial verdict
        never changes between two runs on unchanged files, and other files get other probes. Values a
        learner must not be able to predict (a mystery node's name) come from ``random.SystemRandom``
        instead. A ``src/`` that cannot be read whole (a fifo, a broken link) seeds from the lesson id
        alone; never raises.
        """
        if self._random is None:
            seed = hashlib.sha256(f"{self.lesson.id}\n".encode())
            if self._sources_digest:  # the build already read every file of the lesson's packages
                seed.update(self._sources_digest.encode())
            else:  # a lesson without packages (a script in src/, a file to hand in): read src/ here
                src = self.workspace_root / "src"
                with contextlib.suppress(NotGradable):  # a fifo or a broken link: the build's concern, not ours
                    if src.is_dir():
                        seed.update(scan_package(self.workspace_root, src).content_digest.encode())
            self._random = random.Random(seed.hexdigest())
        return self._random

    def add_plot(self, title: str, times: Sequence[float], series: Mapping[str, Sequence[float]],
                 unit: str = "") -> None:
        """Attach observed time series to the result (rendered as sparklines by ``check``).

        Args:
            title: what is plotted.
            times: seconds from the window start, one per sample.
            series: label -> values, each as long as ``times``.
            unit: unit of the values (e.g. ``"deg"``).

        Raises:
            ValueError: a series' length differs from ``times``.
        """
        times = [float(t) for t in times]
        for label, values in series.items():
            if len(values) != len(times):
                raise ValueError(f"plot {title!r}: series {label!r} has {len(values)} values for {len(times)} times")
        self.plots.append(Plot(title, times, {k: [float(v) for v in vs] for k, vs in series.items()}, unit))

    @contextlib.contextmanager
    def phase(self, name: str) -> Iterator[None]:
        """Time a phase of the grader (accumulated into ``timings[name]``, seconds)."""
        begin = time.monotonic()
        try:
            yield
        finally:
            with self._timings_lock:  # two halves of a lesson may be timed on two threads
                self.timings[name] = self.timings.get(name, 0.0) + time.monotonic() - begin

    # --- the observer's, as graders and the engine name them ------------------------------------------

    @property
    def ros(self) -> Any:
        """The private ROS graph of this check (a :class:`~ros2course.run.probes.RosSession`, created on first
        use, by one thread only; :attr:`~ros2course.grade.observer.Observer.ros`)."""
        return self.observer.ros

    @property
    def graph(self) -> Any:
        """The graph the calling thread's steps observe: the innermost open part's own graph
        (``part(..., own_graph=True)``), else :attr:`ros`."""
        return self.observer.graph

    def new_graph(self) -> Any:
        """Another private ROS graph (its own domain id) for this check, closed with it
        (:meth:`~ros2course.grade.observer.Observer.new_graph`): for a second instance of a learner's node
        that must not see the first, or a lesson's second executable. Pass it as ``graph=`` to the kit steps
        and :meth:`launch`, or open the part with ``part(name, own_graph=True)``."""
        return self.observer.new_graph()

    @property
    def recorder(self) -> Any:
        """The check's MCAP recording (:class:`~ros2course.run.recording.Recorder`), or None before a graph was used."""
        return self.observer.recorder

    @property
    def graph_snapshots(self) -> list[dict[str, Any]]:
        """What the graph showed in each part that launched learner nodes (``graph.json``)."""
        return self.observer.graph_snapshots

    @property
    def diagnose_seconds(self) -> list[float]:
        """Seconds each diagnosis of a failed check took, in order."""
        return self.observer.diagnose_seconds

    # --- the machine view's, as graders name them -----------------------------------------------------

    def overlay(self) -> dict[str, str]:
        """The sourced workspace environment (``install/setup.bash``), without the domain id
        (:meth:`~ros2course.grade.machine.MachineView.overlay`)."""
        return self.machine.overlay()

    def interface_type(self, package: str, kind: str, name: str) -> Any:
        """A generated msg/srv class from the workspace, or from the course's trusted build in batch grading
        (:meth:`~ros2course.grade.machine.MachineView.interface_type`).

        Raises:
            NotGradable: the interface package is not built or does not load.
            CourseError: lesson.yaml does not declare it, or submission code runs sandboxed and the course
                has no build of ``package``.
        """
        return self.machine.interface_type(package, kind, name)

    def installed_type(self, package: str, kind: str, name: str) -> Any:
        """A msg/srv class of the ROS install itself, never the workspace's, e.g. ``("tf2_msgs", "msg",
        "TFMessage")`` (:meth:`~ros2course.grade.machine.MachineView.installed_type`).

        Raises:
            NotGradable: the package is not in the ROS install, or its types do not load.
        """
        return self.machine.installed_type(package, kind, name)

    def reference_package(self, package: str) -> Path:
        """The folder of the course's own reference source of ``package``, read-only
        (:meth:`~ros2course.grade.machine.MachineView.reference_package`).

        Raises:
            CourseError: lesson.yaml does not declare it in ``references:``, or the course has no such package.
        """
        return self.machine.reference_package(package)

    def submission_folder(self, name: str, fill: Callable[[Path], None] | None = None) -> Path:
        """A fresh folder ``log_dir/<name>`` that the programs the grader runs as the submission may write;
        ``fill(folder)`` runs first, as the grader (:meth:`~ros2course.grade.machine.MachineView.submission_folder`).
        """
        return self.machine.submission_folder(name, fill)

    def find_executable(self, package: str, executable: str) -> tuple[Path | None, str]:
        """Resolve ``package``/``executable`` the way ``ros2 run`` does: ``(path or None, what was found)``
        (:meth:`~ros2course.grade.machine.MachineView.find_executable`)."""
        return self.machine.find_executable(package, executable)

    def find_share(self, package: str) -> Path | None:
        """``install/<package>/share/<package>`` as ``ros2 launch`` finds it (ament index), or None."""
        return self.machine.find_share(package)

    def launch(self, path: Path, name: str, args: list[str] | None = None, graph=None) -> LearnerProcess:
        """Start a learner executable in the private domain; it is stopped at the end of the check.

        Args:
            path: the executable (from :meth:`find_executable`).
            name: label for its log files (``<name>.stdout.log``).
            args: extra arguments (e.g. ``["--ros-args", "-r", "__node:=x"]``).
            graph: the :class:`~ros2course.run.probes.RosSession` to run in (default :attr:`graph`).
        """
        self.book.stop_if_settled()
        graph = graph or self.graph
        env = graph.learner_env(self.machine.overlay())
        proc = self.machine.process([str(path), *(args or [])], env, name, ros_sigint=True)
        self.observer.launched(graph, proc)  # the graph and process a failed check of this part is diagnosed with
        proc.start()
        return proc

    def start_program(self, argv: list[str], label: str, *, env: dict[str, str] | None = None,
                      cwd: Path | None = None, deadline: float = 60.0, stdin_open: bool = False) -> LearnerProcess:
        """Start a learner program that is not a ROS node (a script, a compiled binary, pip).

        The same care as nodes: its own process group, capped output in
        ``<label>.stdout.log``, a watchdog SIGKILL ``deadline`` seconds after start,
        and it is stopped with the check. No ROS graph is created.

        Args:
            argv: the command (``argv[0]`` a path or a name on ``env``'s PATH).
            env: its whole environment (default: the ROS install's, without the workspace overlay).
            cwd: working directory (default: the workspace root).
            stdin_open: stdin a pipe nobody writes to, as a terminal nobody types into (a question waits for
                ever), instead of ``/dev/null`` (:class:`~ros2course.run.process.LearnerProcess`).
        """
        self.book.stop_if_settled()
        proc = self.machine.process(argv, dict(self.base_env if env is None else env), label, cwd=cwd,
                                    deadline=deadline, stdin_open=stdin_open)
        proc.start()
        return proc

    def run_colcon(self, args: Sequence[str], *, timeout: float = 120.0) -> subprocess.CompletedProcess:
        """Run ``colcon ARGS`` in the workspace folder as the learner's terminal would, and wait for it, as the
        submission (:meth:`~ros2course.grade.machine.MachineView.run_colcon`).

        Args:
            args: colcon's arguments, global options first (``["--log-base", "/dev/null", "list"]``).
            timeout: seconds before colcon is killed.

        Returns:
            the finished process (``returncode``, ``stdout`` and ``stderr`` as text).

        Raises:
            subprocess.TimeoutExpired: colcon ran longer than ``timeout``.
        """
        self.book.stop_if_settled()
        return self.machine.run_colcon(args, timeout=timeout)

    # --- the end ------------------------------------------------------------------------------------

    def close(self) -> None:
        """Close the grader's ROS graphs, stop every learner process, remove stale shared memory
        (:meth:`~ros2course.grade.observer.Observer.close`: the graphs first, among live peers; the domain
        ids last), and write the recording's check windows and ``graph.json``."""
        self.observer.close(self.machine.stop_processes, self.book)
