"""The object a grader is handed: :class:`GradingSession`.

It owns what a check observes (its parts, their graphs, processes and recording, a
read-only view of the workspace) and records each check's verdict with what was observed,
what was expected and a diagnosis. The public grading module :mod:`ros2course.kit`
re-exports it; :func:`ros2course.grade.engine.grade_lesson` creates one per check.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import logging
import os
import random
import shutil
import subprocess
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from ros2course.build import colcon as build_mod
from ros2course.build.sources import scan_package
from ros2course.errors import CourseError, NotGradable
from ros2course.grade.results import NOT_CHECKED, CheckResult, Plot
from ros2course.lesson.catalog import Lesson, content_root
from ros2course.ros import index as ament_index
from ros2course.ros.interfaces import workspace_type
from ros2course.ros.manifests import find_packages
from ros2course import sandbox
from ros2course.run.diagnose import (
    MAX_FINDINGS,
    Diagnosis,
    GraphSnapshot,
    diagnose,
    process_findings,
    silent_topics,
    snapshot,
)
from ros2course.run.probes import RosSession
from ros2course.run.process import LearnerProcess, sweep_stale_fastdds_shm
from ros2course.run.recording import CHECKS_METADATA, Recorder
from ros2course.run.recording import FILE_NAME as RECORDING_FILE



from ros2course.grade.checklist import Check, StopWhen, Unmet, VerdictSettled, check_dependencies


#: What the learner's nodes showed in the graph, per part, in a check's log folder (``ros2course graph``).
GRAPH_FILE = "graph.json"
#: Set to ``0`` to grade without diagnoses (:meth:`GradingSession._diagnosis`).
DIAGNOSE_ENV = "ROS2COURSE_DIAGNOSE"


@dataclasses.dataclass(frozen=True)
class Band:
    """The interval between events a verdict allowed, kept with its check's recording window.

    Attributes:
        low, high: seconds (a rate's period minus and plus its tolerance, kit.rate).
        of: the statistic of the intervals the band bounded: ``"mean"`` or ``"median"``.
    """

    low: float
    high: float
    of: str = "mean"

    def metadata(self) -> dict[str, Any]:
        """The band's fields in the recording's check metadata (``ros2course evidence --plot`` reads them)."""
        return {"band": [self.low, self.high], "band_of": self.of}


@dataclasses.dataclass
class _PartState:
    """What the engine keeps of one open :meth:`GradingSession.part` (one thread's stack of them).

    Attributes:
        name: the part's name (the ``part`` of the graph snapshots in ``graph.json``).
        graph: the :class:`~ros2course.run.probes.RosSession` its learner processes run in, or None
            before it launched any.
        diagnosed: a failed check of it got its diagnosis (one per part: issue 19).
        observed: its graph was observed (:meth:`GradingSession._observe_graph`).
        processes: the learner processes it launched (their exits feed the ``process`` diagnosis).
        own_graph: the private graph the part was opened with (``part(..., own_graph=True)``), or None:
            what :attr:`GradingSession.graph` gives the steps inside it.
    """

    name: str
    graph: Any = None
    own_graph: Any = None
    diagnosed: bool = False
    observed: bool = False
    processes: list[LearnerProcess] = dataclasses.field(default_factory=list)


class GradingSession:
    """What a grader's ``grade()`` works with.

    Attributes:
        lesson: the :class:`~ros2course.lesson.catalog.Lesson`.
        workspace_root: the colcon workspace being graded.
        log_dir: this check's log folder (node stdout/stderr go here).
        ros: the :class:`~ros2course.run.probes.RosSession` (private domain), started on first use.
        base_env: the ROS install's environment (no workspace overlay).

    ``stop_when`` (``dev validate --until-settled`` only): grading stops at the grader's next step once
    the verdicts recorded settle the case (:meth:`_stop_if_settled`); None for every real grading.
    """

    def __init__(self, lesson: Lesson, checks: list[Check], workspace_root: Path, log_dir: Path,
                 base_env: dict[str, str], trusted_interfaces: Path | None = None, sources_digest: str = "",
                 stop_when: StopWhen | None = None) -> None:
        self.lesson = lesson
        # dev validate --until-settled: stop grading once the case's verdict is settled (see _stop_if_settled)
        self._stop_when = stop_when
        self._grading_thread = threading.current_thread()
        # the build's digest of the lesson's package contents (BuildResult.content_digest): seeds :attr:`random`
        self._sources_digest = sources_digest
        check_dependencies(checks)
        self.checks = {c.id: c for c in checks}
        self._order = [c.id for c in checks]
        # Closing actions of the open parts, innermost last (see :meth:`part`), per thread:
        # a lesson's two halves may be graded on two threads at once, each in its own part.
        self._local = threading.local()
        # parts graded at once (kit.parts.at_once) may first touch ros, a new graph or the recording together:
        # one of each must be made, and the ExitStack that closes them is not thread-safe
        self._making = threading.RLock()
        self._timings_lock = threading.Lock()
        self.workspace_root = workspace_root
        self.log_dir = log_dir
        self.base_env = base_env
        self.trusted_interfaces = trusted_interfaces
        self.results: dict[str, CheckResult] = {}
        self._processes: list[LearnerProcess] = []
        self._stack = contextlib.ExitStack()
        # the domain ids of the check's graphs, released only once its processes are stopped (RosSession)
        self._domains = contextlib.ExitStack()
        self._ros = None
        self._overlay: dict[str, str] | None = None
        self.notes: list[str] = []
        #: seconds per named phase (``start``, ``observe``, ``stop``...), see :meth:`phase`.
        self.timings: dict[str, float] = {}
        #: time series to show under the table of checks, see :meth:`add_plot`.
        self.plots: list[Plot] = []
        #: check id -> wall-clock window (ns) its verdict judged, see :meth:`record`.
        self.windows: dict[str, tuple[int, int]] = {}
        self._started_ns = time.time_ns()
        #: the check's MCAP recording, made when the grader first uses the ROS graph (:attr:`ros`).
        self.recorder: Recorder | None = None
        #: seconds each diagnosis of a failed check took (:meth:`_diagnosis`), in order.
        self.diagnose_seconds: list[float] = []
        #: what the graph showed in each part that launched learner nodes (:meth:`_observe_graph`):
        #: ``{"part", "nodes", "ends"}``, written to ``graph.json`` by :meth:`close`.
        self.graph_snapshots: list[dict[str, Any]] = []
        #: ``check id -> Band``: the seconds between events a verdict allowed (:meth:`record`'s ``band``)
        #: and which statistic of the intervals it bounded.
        self.bands: dict[str, Band] = {}
        self._random: random.Random | None = None

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

    # --- recording ---------------------------------------------------------

    def record(self, check_id: str, passed: bool, observed: str, expected: str, hint: str | None = None,
               fraction: float | None = None, window: tuple[float, float] | None = None,
               band: tuple[float, float] | None = None, band_of: str = "mean") -> bool:
        """Record the verdict on ``check_id``; returns ``passed``.

        A failed verdict may get the engine's diagnosis of the graph (see :meth:`_diagnosis`);
        it never changes the verdict or the points.

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
        self._stop_if_settled()
        check = self.checks[check_id]
        blocker = self.unmet_need(check_id)
        if blocker is not None:
            self._not_checked(check_id, blocker)
            return False
        previous = self.results.get(check_id)
        if previous is not None and previous.skipped:
            return False  # the engine marked it "not checked" (its part stopped): that verdict stays
        share = (1.0 if passed else 0.0) if fraction is None else max(0.0, min(1.0, fraction))
        now = time.time_ns()
        start = getattr(self._local, "mark", self._started_ns)
        self._local.mark = now
        self.windows[check_id] = (int(window[0] * 1e9), int(window[1] * 1e9)) if window else (start, now)
        if band is not None:
            self.bands[check_id] = Band(float(band[0]), float(band[1]), band_of)
        fresh = self._observe_graph()
        self.results[check_id] = CheckResult(check.id, check.name, round(check.points * share, 3), check.points,
                                             passed, observed, expected,
                                             "" if passed else (hint if hint is not None else check.hint),
                                             diagnosis=[] if passed else self._diagnosis(check, fresh),
                                             visibility=check.visibility)
        return passed

    def _part_graph(self) -> tuple[_PartState, Any] | None:
        """The calling thread's innermost open part and the graph its learner processes run in (its own
        :meth:`launch`, else an enclosing part's); None outside a part or before any launch."""
        states = self._part_states
        if not states:
            return None
        graph = next((state.graph for state in reversed(states) if state.graph is not None), None)
        return None if graph is None else (states[-1], graph)

    def _observe_graph(self) -> GraphSnapshot | None:
        """Keep what the graph shows at the first verdict of a part that launched learner nodes; return it
        when taken by this call (the snapshot a diagnosis of the same verdict reuses), else None.

        The observed side of ``ros2course graph`` (issue 19): one
        :class:`~ros2course.run.diagnose.GraphSnapshot` per part, in :attr:`graph_snapshots`,
        written to ``graph.json`` in the check's log folder by :meth:`close`. The first
        verdict after a launch is when the grader has waited for the learner's nodes, and
        before any Ctrl+C it presses. Never raises; costs a few rcl graph queries per part.
        """
        found = self._part_graph()
        if found is None or found[0].observed:
            return None
        state, graph = found
        state.observed = True
        taken = snapshot(graph)
        if taken is not None:
            with self._timings_lock:
                self.graph_snapshots.append({"part": state.name, **taken.to_dict()})
        return taken

    def _diagnosis(self, check: Check, fresh: GraphSnapshot | None = None) -> list[Diagnosis]:
        """What the part shows against the lesson's ``graph:`` contract, for a failed ``check`` (issue 19).

        Made at most once per part (the innermost open :meth:`part` of this
        thread): for its first failed check recorded while the part, or a part
        around it, runs a learner process in a graph (:meth:`launch`). The graph
        is the snapshot :meth:`_observe_graph` took for this same verdict (``fresh``),
        else one taken now; QoS profiles are queried only for the expected topics
        that are there; the part's learner processes and its silent topics are
        judged too (:func:`ros2course.run.diagnose.diagnose`), with the contract
        entries of the check's own part (:meth:`ros2course.lesson.catalog.LessonGraph.for_part`).
        A lesson without a ``graph:``, or a part whose processes the grader already stopped
        (its Ctrl+C check), gets the process findings only. ``[]`` when the check
        watched no graph, or anything fails (logged at debug level): a diagnosis never changes a verdict or a score.
        Seconds spent: each in :attr:`diagnose_seconds`, their sum in ``timings["diagnose"]``.
        ``ROS2COURSE_DIAGNOSE=0`` turns it off (to show verdicts are the same without it).
        """
        try:
            contract = self.lesson.graph
            found = self._part_graph()
            if found is None or found[0].diagnosed or os.environ.get(DIAGNOSE_ENV) == "0":
                return []
            state, graph = found
            state.diagnosed = True
            begin = time.monotonic()
            with self.phase("diagnose"):
                processes = [p for part in self._part_states for p in part.processes]
                own = state.processes or processes
                # after the grader's own Ctrl+C the graph is emptying: what is missing then is no cause
                stopped = bool(own) and all(p.signalled_at is not None for p in own)
                if contract is None or stopped:  # no graph to compare: the learner's processes only
                    result = process_findings(processes)[:MAX_FINDINGS]
                else:
                    taken = fresh if fresh is not None else snapshot(graph)
                    silent = silent_topics(graph)
                    result = diagnose(taken, contract.for_part(check.part), ros_node=graph.node,
                                      processes=processes, silent=silent)
            with self._timings_lock:
                self.diagnose_seconds.append(time.monotonic() - begin)
            return result
        except Exception:  # noqa: BLE001 - advice only: never fail the check's recording
            logging.getLogger(__name__).debug("diagnosis of %s failed", check.id, exc_info=True)
            return []

    @property
    def _part_states(self) -> list[_PartState]:
        """The calling thread's open parts, innermost last."""
        if not hasattr(self._local, "parts"):
            self._local.parts = []
        return self._local.parts

    def amend(self, check_id: str, *, observed: str | None = None, hint: str | None = None) -> None:
        """Add to a recorded verdict's explanation; its points and pass/fail stay.

        Args:
            observed: replaces the observed text (e.g. the first text plus what else was found).
            hint: replaces the hint.

        Raises:
            KeyError: ``check_id`` has no verdict yet.
        """
        result = self.results[check_id]
        self.results[check_id] = dataclasses.replace(
            result, observed=result.observed if observed is None else observed,
            hint=result.hint if hint is None else hint)

    def unmet_need(self, check_id: str) -> str | None:
        """Why ``check_id`` cannot be judged: a sentence naming the first of its needs that did not pass.

        None while every need passed or is still to be judged. Needs are
        followed through: a need that was itself not checked blocks too.
        """
        for need in self.checks[check_id].needs:
            result = self.results.get(need)
            if result is not None and not result.passed:
                return (f"'{self.checks[need].name}' was not checked" if result.skipped
                        else f"'{self.checks[need].name}' failed")
            if result is None and (blocked := self.unmet_need(need)) is not None:
                return blocked
        return None

    def _stop_if_settled(self) -> None:
        """Raise :class:`~ros2course.grade.checklist.VerdictSettled` when the verdicts recorded so far settle
        ``stop_when``, on the thread that runs ``grade()`` (a worker thread's half runs on until it ends).

        Called as the grader takes its next step (records another check, requires one, opens a part,
        reaches for a graph, starts a process), never by :meth:`amend`: a verdict's own amendment, made
        right after it, is kept. Raises once: it disarms itself.
        """
        if (self._stop_when and threading.current_thread() is self._grading_thread
                and self._stop_when.reached(self.results)):
            self._stop_when = None
            raise VerdictSettled

    def _not_checked(self, check_id: str, reason: str) -> None:
        check = self.checks[check_id]
        self.results[check_id] = CheckResult(check.id, check.name, 0.0, check.points, False,
                                             f"{NOT_CHECKED}{reason}", "(depends on the failed check above)",
                                             check.hint, skipped=True, visibility=check.visibility)

    def require(self, *check_ids: str) -> None:
        """Go on only if every check in ``check_ids`` passed.

        Raises:
            Unmet: one of them failed or is not recorded; the current :meth:`part` ends.
        """
        self._stop_if_settled()
        for check_id in check_ids:
            result = self.results.get(check_id)
            if result is None or not result.passed:
                raise Unmet(self.unmet_need(check_id) or f"'{self.checks[check_id].name}' did not pass")

    @contextlib.contextmanager
    def part(self, name: str = "", *, own_graph: bool = False) -> Iterator[None]:
        """Grade one independent part of a lesson (e.g. one of two executables).

        :class:`Unmet` raised inside ends only this part. On the way out the
        part's closing actions (:meth:`on_close`, e.g. judging Ctrl+C of a
        node it started) run, newest first, whatever happened.

        Args:
            name: the part's name (feedback, ``graph.json``).
            own_graph: the part gets a private graph of its own (:meth:`new_graph`);
                :attr:`graph`, and so every kit step and :meth:`launch` inside it,
                use that graph without a ``graph=`` argument.
        """
        self._stop_if_settled()
        self._closers.append([])
        self._part_states.append(_PartState(name, own_graph=self.new_graph() if own_graph else None))
        self._local.mark = time.time_ns()
        try:
            yield
        except Unmet as stop:
            self._run_closers(self._closers.pop())
            self.stop_part(name, str(stop))
        except BaseException:
            # Any other end (VerdictSettled, a grader's crash, KeyboardInterrupt) closes the part too, every
            # action however another fails, and lets the end go on: a world, a stand-in server or a probe
            # still spinning on the part's graph when close() shuts that graph down crashed the grading
            # process (SIGSEGV: a physics world's stepping thread publishing on the context being destroyed,
            # seen twice in CI under dev validate --until-settled).
            self._run_closers(self._closers.pop(), keep_going=True)
            raise
        else:
            self._run_closers(self._closers.pop())
        finally:
            self._part_states.pop()

    @property
    def _closers(self) -> list[list[Any]]:
        """The calling thread's stack of open parts' closing actions."""
        if not hasattr(self._local, "closers"):
            self._local.closers = []
        return self._local.closers

    def stop_part(self, name: str, reason: str) -> None:
        """Record every unrecorded check of part ``name`` ("" = every part) as not checked because of ``reason``.

        A check whose own needs failed gets that reason instead.
        """
        for check_id in self._order:
            if check_id not in self.results and (not name or self.checks[check_id].part == name):
                self._not_checked(check_id, self.unmet_need(check_id) or reason)
        self._stop_if_settled()

    def leave_unjudged(self, reason: str) -> None:
        """Record every check not recorded yet as not checked because of ``reason``, whatever its needs: the
        end of a grading stopped early (``dev validate --until-settled``), where no check after the stop was judged.
        """
        for check_id in self._order:
            if check_id not in self.results:
                self._not_checked(check_id, reason)

    def on_close(self, action: Any) -> None:
        """Run ``action()`` when the current :meth:`part` (or ``grade()``) ends, even after :class:`Unmet`."""
        self._closers[-1].append(action)

    def _run_closers(self, closers: list[Any], keep_going: bool = False) -> None:
        """Run ``closers`` newest first; :class:`Unmet` from one never stops the others (nor, with
        ``keep_going``, any ``Exception``: the part is already ending with an error of its own)."""
        for action in reversed(closers):
            with contextlib.suppress(Exception if keep_going else Unmet):
                action()

    def ordered_results(self) -> list[CheckResult]:
        """Every declared check's result, in declaration order; unrecorded ones become "not checked".

        A failed verdict carries its ``evidence`` (the recording and the window it judged).
        """
        for check_id in self._order:
            if check_id not in self.results:
                self._not_checked(check_id, self.unmet_need(check_id) or "the grader stopped before this check")
        out = []
        for check_id in self._order:
            result = self.results[check_id]
            if self.recorder is not None and not result.passed and not result.skipped and check_id in self.windows:
                start, end = self.windows[check_id]
                result = dataclasses.replace(result, evidence={"recording": str(self.recorder.path),
                                                               "start_ns": start, "end_ns": end})
            out.append(result)
        return out

    # --- environment and processes ----------------------------------------

    @property
    def ros(self):
        """The private ROS graph of this check (created on first use, by one thread only)."""
        with self._making:
            if self._ros is None:
                self._ros = self._stack.enter_context(RosSession(recorder=self._recording(),
                                                                domain_holder=self._domains))
        return self._ros

    def _recording(self) -> Recorder | None:
        """The check's recorder (``<log_dir>/observed.mcap``), created on first use.

        ``ROS2COURSE_RECORD=0`` turns recording off (benchmarks/check_speed.py measures its cost).
        """
        if os.environ.get("ROS2COURSE_RECORD", "1") == "0":
            return None
        with self._making:
            if self.recorder is None:
                self.log_dir.mkdir(parents=True, exist_ok=True)
                self.recorder = Recorder(self.log_dir / RECORDING_FILE)
        return self.recorder

    def overlay(self) -> dict[str, str]:
        """The sourced workspace environment (``install/setup.bash``), without the domain id."""
        if self._overlay is None:
            self._overlay = build_mod.overlay_env(self.workspace_root, self.base_env)
        return dict(self._overlay)

    def interface_type(self, package: str, kind: str, name: str) -> Any:
        """A generated msg/srv class from the workspace (see :mod:`ros2course.ros.interfaces`).

        With ``trusted_interfaces`` (batch grading) the class comes from the
        course's own build of the package, never from the submission's: its
        generated Python and C code would run inside the grader.

        Raises:
            NotGradable: the interface package is not built or does not load.
            CourseError: submission code runs sandboxed and the course has no build of ``package``.
        """

        if package not in self.lesson.interfaces:
            # the same refusal under check and batch: an undeclared package fails dev validate, not a class
            raise CourseError(f"the grader of {self.lesson.id} imports {package} types but its lesson.yaml does not "
                              f"declare them", f"a fault of the course: add 'interfaces: [{package}]' to lesson.yaml")
        if self.trusted_interfaces is not None:
            return workspace_type(build_mod.overlay_env(self.trusted_interfaces, self.base_env), package, kind, name)
        if sandbox.current() is not None:
            raise CourseError(f"the grader needs {package} types but the batch built no trusted copy of {package}",
                              "a fault of the grading run: grade through ros2course grade, which builds them")
        return workspace_type(self.overlay(), package, kind, name)

    def installed_type(self, package: str, kind: str, name: str) -> Any:
        """A msg/srv class of the ROS install itself (the wheels, the underlay, a system ROS), never the
        workspace's: e.g. ``("tf2_msgs", "msg", "TFMessage")``, which only the source-built underlay has.

        Loaded as :meth:`interface_type` loads a workspace's (:mod:`ros2course.ros.interfaces`): the grading
        process started before the install's ``lib/`` could be on its library path, so the package's
        typesupport libraries are loaded from its prefix. Nothing of a submission is involved, so batch
        grading uses it as is.

        Raises:
            NotGradable: the package is not in the ROS install, or its types do not load.
        """
        return workspace_type(self.base_env, package, kind, name)

    def reference_package(self, package: str) -> Path:
        """The folder of the course's own reference source of ``package`` (``solutions/src/...``), read-only.

        For a grader that runs something of the learner's against the course's code (a testing
        lesson: the learner's tests against the reference and its mutants). In batch grading the
        copy in the trusted build is used: ``solutions/`` is hidden from the sandbox.

        Raises:
            CourseError: the lesson does not declare ``package`` in ``references:`` (lesson.yaml), or the
                course has no such reference package (both faults of the course, never the learner's).
        """
        if package not in self.lesson.references:
            raise CourseError(f"the grader of {self.lesson.id} reads the reference of {package} but its lesson.yaml "
                              "does not declare it", f"a fault of the course: add 'references: [{package}]' to lesson.yaml")
        src = (self.trusted_interfaces / "src" if self.trusted_interfaces is not None
               else content_root() / "solutions" / "src")
        found = find_packages(src)
        if package not in found:
            raise CourseError(f"the course has no reference package {package} in {src}",
                              "a fault of the course or of the grading run: grade through ros2course grade, which "
                              "copies the lesson's references")
        return found[package][0]

    def submission_folder(self, name: str, fill: Callable[[Path], None] | None = None) -> Path:
        """A fresh folder ``log_dir/<name>`` that the programs the grader runs as the submission may write.

        For every file a submission's program writes while the grader observes it: a
        CMake build folder, a venv, a probe's trace, a copy of the learner's sources
        that a build writes into, a ``ROS_HOME``. ``fill(folder)`` runs first, as the
        grader (copy sources, templates); then, in batch grading, the whole tree is
        given to the submission's uid (:func:`ros2course.sandbox.give_tree`) and the
        grader only reads it from then on (writing into a folder the submission owns
        could follow a link it planted). Under ``check`` the learner owns everything
        already, so both paths see the same folders.

        Args:
            name: a folder name relative to the check's log folder (``"cmake-build"``);
                an earlier folder of that name is removed first.
            fill: called with the new, empty folder before it changes hands.

        Returns:
            the folder (absolute).
        """
        folder = self.log_dir / name
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
        if fill is not None:
            fill(folder)
        sandbox.give_tree(folder)
        return folder

    def find_executable(self, package: str, executable: str) -> tuple[Path | None, str]:
        """Resolve ``package``/``executable`` the way ``ros2 run`` does.

        The package's prefix in the workspace overlay's ament index
        (:func:`ros2course.ros.index.package_prefix`, as ``get_package_prefix``), then
        ``<prefix>/lib/<package>/<executable>`` (ros2run source).

        Returns:
            ``(path, observed)``: the path (None when not found) and a sentence
            saying what was found, for the check's "observed".
        """
        prefix = ament_index.package_prefix(package, self.overlay())
        if prefix is None:
            return None, f"package {package} is not in the ament index (was it built and installed?)"
        lib = prefix / "lib" / package
        candidate = lib / executable
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate, f"{candidate.relative_to(self.workspace_root) if candidate.is_relative_to(self.workspace_root) else candidate}"
        others = sorted(p.name for p in lib.iterdir() if p.is_file()) if lib.is_dir() else []
        listing = ", ".join(others) if others else "nothing"
        return None, f"no executable {executable} in {lib}; found: {listing}"

    def find_share(self, package: str) -> Path | None:
        """``install/<package>/share/<package>`` as ``ros2 launch`` finds it (ament index), or None."""
        return ament_index.package_share(package, self.overlay())

    @property
    def graph(self) -> Any:
        """The graph the calling thread's steps observe: the innermost open part's own graph
        (``part(..., own_graph=True)``), else :attr:`ros` (a :class:`~ros2course.run.probes.RosSession`)."""
        self._stop_if_settled()
        own = next((state.own_graph for state in reversed(self._part_states) if state.own_graph is not None), None)
        return own if own is not None else self.ros

    def new_graph(self):
        """Another private ROS graph (its own domain id) for this check, closed with it.

        For running a second instance of a learner's node at the same time as the
        first without either seeing the other (e.g. the parameters lesson's run
        with ``-p`` overrides), or a lesson's second executable: a process joining
        a graph whose participants already know each other is discovered up to
        ~3 s later than one joining a fresh graph (Fast DDS, localhost discovery).
        Pass it as ``graph=`` to the kit steps and :meth:`launch`, or open the part
        with ``part(name, own_graph=True)``, which makes one and uses it by default.
        """
        self._stop_if_settled()
        with self._making:
            return self._stack.enter_context(RosSession(recorder=self._recording(), domain_holder=self._domains))

    def launch(self, path: Path, name: str, args: list[str] | None = None, graph=None) -> LearnerProcess:
        """Start a learner executable in the private domain; it is stopped at the end of the check.

        Args:
            path: the executable (from :meth:`find_executable`).
            name: label for its log files (``<name>.stdout.log``).
            args: extra arguments (e.g. ``["--ros-args", "-r", "__node:=x"]``).
            graph: the :class:`~ros2course.run.probes.RosSession` to run in (default :attr:`graph`).
        """
        self._stop_if_settled()
        graph = graph or self.graph
        env = graph.learner_env(self.overlay())
        if self._part_states:  # the graph a failed check of this part is diagnosed in (see _diagnosis)
            self._part_states[-1].graph = graph
        proc = LearnerProcess([str(path), *(args or [])], env, self.log_dir, name,
                              cwd=self.workspace_root, ros_sigint=True)
        self._processes.append(proc)
        if self._part_states:  # judged by the part's process diagnosis
            self._part_states[-1].processes.append(proc)
        proc.start()
        return proc

    def start_program(self, argv: list[str], label: str, *, env: dict[str, str] | None = None,
                      cwd: Path | None = None, deadline: float = 60.0) -> LearnerProcess:
        """Start a learner program that is not a ROS node (a script, a compiled binary, pip).

        The same care as nodes: its own process group, capped output in
        ``<label>.stdout.log``, a watchdog SIGKILL ``deadline`` seconds after start,
        and it is stopped with the check. No ROS graph is created.

        Args:
            argv: the command (``argv[0]`` a path or a name on ``env``'s PATH).
            env: its whole environment (default: the ROS install's, without the workspace overlay).
            cwd: working directory (default: the workspace root).
        """
        self._stop_if_settled()
        proc = LearnerProcess(list(argv), dict(self.base_env if env is None else env), self.log_dir, label,
                              cwd=cwd or self.workspace_root, deadline=deadline)
        self._processes.append(proc)
        proc.start()
        return proc

    def run_colcon(self, args: Sequence[str], *, timeout: float = 120.0) -> subprocess.CompletedProcess:
        """Run ``colcon ARGS`` in the workspace folder as the learner's terminal would, and wait for it.

        colcon runs each package's ``setup.py`` (the submission's code), so it runs as the
        submission (:mod:`ros2course.sandbox`), with the ROS install's environment
        (:attr:`base_env`, no workspace overlay) and no standard input.

        Args:
            args: colcon's arguments, global options first (``["--log-base", "/dev/null", "list"]``).
            timeout: seconds before colcon is killed.

        Returns:
            the finished process (``returncode``, ``stdout`` and ``stderr`` as text).

        Raises:
            subprocess.TimeoutExpired: colcon ran longer than ``timeout``.
        """
        self._stop_if_settled()
        return sandbox.run([*build_mod.colcon_command(self.base_env), *args], cwd=self.workspace_root,
                           env=dict(self.base_env), capture_output=True, text=True, timeout=timeout, check=False,
                           stdin=subprocess.DEVNULL)

    def close(self) -> None:
        """Close the grader's ROS graphs, stop every learner process, remove stale shared memory.

        The graphs close first, while every learner process (and the check's ``ros2``
        daemon) still runs: the grader's DDS participant is then destroyed among live
        peers. Destroyed just after a peer was killed, Fast DDS 2.14 (Jazzy) may crash
        the whole grading process in ``SharedMemChannelResource::release`` (a shared-memory
        port the killed peer shared being regenerated meanwhile; core dump of a segfault
        seen in 1 of about 30 ``inspect-services`` gradings under load, and in CI).
        The graphs' domain ids are released last, once no process of the check is left in them
        (:class:`~ros2course.run.probes.RosSession`'s ``domain_holder``).
        """
        try:
            self._stack.close()
            for proc in self._processes:
                proc.stop(sigint_timeout=2.0, sigterm_timeout=2.0)
        finally:
            self._domains.close()  # last: no process of this check (its ros2 daemon included) is left in them
        if self.recorder is not None:  # after the graphs: no callback writes any more
            self.recorder.metadata(CHECKS_METADATA, {
                check_id: json.dumps({"start_ns": start, "end_ns": end, "passed": self.results[check_id].passed,
                                      "observed": self.results[check_id].observed,
                                      **(self.bands[check_id].metadata() if check_id in self.bands else {})})
                for check_id, (start, end) in self.windows.items() if check_id in self.results})
            self.recorder.close()
        if self.graph_snapshots:
            with contextlib.suppress(OSError):
                self.log_dir.mkdir(parents=True, exist_ok=True)
                (self.log_dir / GRAPH_FILE).write_text(json.dumps(
                    {"lesson": self.lesson.id, "parts": self.graph_snapshots}, indent=1), encoding="utf-8")
        sweep_stale_fastdds_shm()
