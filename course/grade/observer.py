"""The grading's observer: :class:`Observer`, the part of a grading session that watches the ROS graph.

It owns the check's private ROS graphs (:class:`~ros2course.run.probes.RosSession`, each on a domain id
of its own, closed before the domain ids are released), its MCAP recording, the parts' graph snapshots
(``graph.json``, what ``ros2course graph`` shows) and the diagnosis of a failed check (issue 19).
:class:`~ros2course.grade.session.GradingSession` composes it with the verdict book
(:mod:`ros2course.grade.verdicts`), which calls :meth:`Observer.on_verdict` at each verdict, and the
machine view (:mod:`ros2course.grade.machine`), whose processes it stops when it closes.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import logging
import os
import threading
import time
from collections.abc import Callable
from contextlib import AbstractContextManager
from pathlib import Path
from typing import Any

from ros2course.grade.checklist import Check
from ros2course.grade.verdicts import VerdictBook
from ros2course.lesson.catalog import Lesson
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

#: What the learner's nodes showed in the graph, per part, in a check's log folder (``ros2course graph``).
GRAPH_FILE = "graph.json"
#: Set to ``0`` to grade without diagnoses (:meth:`Observer.diagnosis`).
DIAGNOSE_ENV = "ROS2COURSE_DIAGNOSE"


@dataclasses.dataclass
class _PartState:
    """What the engine keeps of one open :meth:`GradingSession.part` (one thread's stack of them).

    Attributes:
        name: the part's name (the ``part`` of the graph snapshots in ``graph.json``).
        graph: the :class:`~ros2course.run.probes.RosSession` its learner processes run in, or None
            before it launched any.
        diagnosed: a failed check of it got its diagnosis (one per part: issue 19).
        observed: its graph was observed (:meth:`Observer.observe_graph`).
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


class Observer:
    """One grading's view of the ROS graph: its graphs, recording, graph snapshots and diagnoses.

    Args:
        lesson: the lesson (its ``graph:`` contract, compared with what a failed check's part shows).
        log_dir: the check's log folder (``observed.mcap``, ``graph.json``).
        stop_if_settled: called before a graph is reached for (the verdict book's: ``dev validate
            --until-settled`` stops there once settled).
        phase: ``phase(name)``, a context manager timing a phase (diagnoses are timed as ``diagnose``).

    Attributes:
        recorder: the check's MCAP recording, made when a graph is first used; None before (or with
            ``ROS2COURSE_RECORD=0``).
        graph_snapshots: ``{"part", "nodes", "ends"}`` per part that launched learner nodes (:meth:`observe_graph`).
        diagnose_seconds: seconds each diagnosis took, in order.
    """

    def __init__(self, lesson: Lesson, log_dir: Path, stop_if_settled: Callable[[], None],
                 phase: Callable[[str], AbstractContextManager[None]]) -> None:
        self.lesson = lesson
        self.log_dir = log_dir
        self._stop_if_settled = stop_if_settled
        self._phase = phase
        # the open parts' graphs and processes, innermost last, per thread (a lesson's two halves may be
        # graded on two threads at once, each in its own part)
        self._local = threading.local()
        # parts graded at once (kit.parts.at_once) may first touch ros, a new graph or the recording together:
        # one of each must be made, and the ExitStack that closes them is not thread-safe
        self._making = threading.RLock()
        self._lock = threading.Lock()
        self._stack = contextlib.ExitStack()
        # the domain ids of the check's graphs, released only once its processes are stopped (RosSession)
        self._domains = contextlib.ExitStack()
        self._ros: RosSession | None = None
        self.recorder: Recorder | None = None
        self.diagnose_seconds: list[float] = []
        self.graph_snapshots: list[dict[str, Any]] = []

    # --- parts ---------------------------------------------------------------------------------------

    def open_part(self, name: str, *, own_graph: bool = False) -> None:
        """Start watching part ``name`` on the calling thread; ``own_graph``: give it a private graph
        (:meth:`new_graph`) that :attr:`graph` returns inside it."""
        self.part_states.append(_PartState(name, own_graph=self.new_graph() if own_graph else None))

    def close_part(self) -> None:
        """Stop watching the calling thread's innermost part."""
        self.part_states.pop()

    def launched(self, graph: Any, proc: LearnerProcess) -> None:
        """Note that the innermost part started learner process ``proc`` in ``graph``: the graph and process
        a failed check of the part is diagnosed with. Nothing outside a part."""
        if self.part_states:
            self.part_states[-1].graph = graph
            self.part_states[-1].processes.append(proc)

    def on_verdict(self, check: Check, passed: bool) -> list[Diagnosis]:
        """The verdict book's call at each verdict: keep the part's graph at its first verdict, and give a
        failed check its diagnosis (:meth:`diagnosis`)."""
        fresh = self.observe_graph()
        return [] if passed else self.diagnosis(check, fresh)

    def part_graph(self) -> tuple[_PartState, Any] | None:
        """The calling thread's innermost open part and the graph its learner processes run in (its own
        launch, :meth:`launched`, else an enclosing part's); None outside a part or before any launch."""
        states = self.part_states
        if not states:
            return None
        graph = next((state.graph for state in reversed(states) if state.graph is not None), None)
        return None if graph is None else (states[-1], graph)

    def observe_graph(self) -> GraphSnapshot | None:
        """Keep what the graph shows at the first verdict of a part that launched learner nodes; return it
        when taken by this call (the snapshot a diagnosis of the same verdict reuses), else None.

        The observed side of ``ros2course graph`` (issue 19): one
        :class:`~ros2course.run.diagnose.GraphSnapshot` per part, in :attr:`graph_snapshots`,
        written to ``graph.json`` in the check's log folder by :meth:`close`. The first
        verdict after a launch is when the grader has waited for the learner's nodes, and
        before any Ctrl+C it presses. Never raises; costs a few rcl graph queries per part.
        """
        found = self.part_graph()
        if found is None or found[0].observed:
            return None
        state, graph = found
        state.observed = True
        taken = snapshot(graph)
        if taken is not None:
            with self._lock:
                self.graph_snapshots.append({"part": state.name, **taken.to_dict()})
        return taken

    def diagnosis(self, check: Check, fresh: GraphSnapshot | None = None) -> list[Diagnosis]:
        """What the part shows against the lesson's ``graph:`` contract, for a failed ``check`` (issue 19).

        Made at most once per part (the innermost open :meth:`GradingSession.part` of this
        thread): for its first failed check recorded while the part, or a part
        around it, runs a learner process in a graph (:meth:`GradingSession.launch`). The graph
        is the snapshot :meth:`observe_graph` took for this same verdict (``fresh``),
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
            found = self.part_graph()
            if found is None or found[0].diagnosed or os.environ.get(DIAGNOSE_ENV) == "0":
                return []
            state, graph = found
            state.diagnosed = True
            begin = time.monotonic()
            with self._phase("diagnose"):
                processes = [p for part in self.part_states for p in part.processes]
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
            with self._lock:
                self.diagnose_seconds.append(time.monotonic() - begin)
            return result
        except Exception:  # noqa: BLE001 - advice only: never fail the check's recording
            logging.getLogger(__name__).debug("diagnosis of %s failed", check.id, exc_info=True)
            return []

    @property
    def part_states(self) -> list[_PartState]:
        """The calling thread's open parts, innermost last."""
        if not hasattr(self._local, "parts"):
            self._local.parts = []
        return self._local.parts

    @property
    def ros(self):
        """The private ROS graph of this check (created on first use, by one thread only)."""
        with self._making:
            if self._ros is None:
                self._ros = self._stack.enter_context(RosSession(recorder=self.recording(),
                                                                domain_holder=self._domains))
        return self._ros

    def recording(self) -> Recorder | None:
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

    @property
    def graph(self) -> Any:
        """The graph the calling thread's steps observe: the innermost open part's own graph
        (``part(..., own_graph=True)``), else :attr:`ros` (a :class:`~ros2course.run.probes.RosSession`)."""
        self._stop_if_settled()
        own = next((state.own_graph for state in reversed(self.part_states) if state.own_graph is not None), None)
        return own if own is not None else self.ros

    def new_graph(self):
        """Another private ROS graph (its own domain id) for this check, closed with it.

        For running a second instance of a learner's node at the same time as the
        first without either seeing the other (e.g. the parameters lesson's run
        with ``-p`` overrides), or a lesson's second executable: a process joining
        a graph whose participants already know each other is discovered up to
        ~3 s later than one joining a fresh graph (Fast DDS, localhost discovery).
        Pass it as ``graph=`` to the kit steps and ``launch``, or open the part
        with ``part(name, own_graph=True)``, which makes one and uses it by default.
        """
        self._stop_if_settled()
        with self._making:
            return self._stack.enter_context(RosSession(recorder=self.recording(), domain_holder=self._domains))

    def close(self, stop_processes: Callable[[], None], book: VerdictBook) -> None:
        """Close the grader's ROS graphs, stop every learner process (``stop_processes()``), release the domain
        ids, write the recording's check metadata (from ``book``'s windows, bands and verdicts) and
        ``graph.json``, and remove stale Fast DDS shared memory.

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
            stop_processes()
        finally:
            self._domains.close()  # last: no process of this check (its ros2 daemon included) is left in them
        results = book.results
        if self.recorder is not None:  # after the graphs: no callback writes any more
            self.recorder.metadata(CHECKS_METADATA, {
                check_id: json.dumps({"start_ns": start, "end_ns": end, "passed": results[check_id].passed,
                                      "observed": results[check_id].observed,
                                      **(book.bands[check_id].metadata() if check_id in book.bands else {})})
                for check_id, (start, end) in book.windows.items() if check_id in results})
            self.recorder.close()
        if self.graph_snapshots:
            with contextlib.suppress(OSError):
                self.log_dir.mkdir(parents=True, exist_ok=True)
                (self.log_dir / GRAPH_FILE).write_text(json.dumps(
                    {"lesson": self.lesson.id, "parts": self.graph_snapshots}, indent=1), encoding="utf-8")
        sweep_stale_fastdds_shm()
