"""Probes: the grader's eyes and hands on a private ROS 2 graph.

A :class:`RosSession` owns one check's graph: a free ``ROS_DOMAIN_ID`` held
through ``domain_coordinator`` for the session's lifetime, an rclpy
``Context`` initialised on that domain, a hidden grader node and an executor
spinning in a background thread. Probes subscribe, call and watch through
that node with rclpy's own APIs; they never shell out to the ``ros2`` CLI
(which the PyPI wheels do not have).

Everything here is black-box: the same probes grade Python and C++ nodes.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import logging
import os
import random
import statistics
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

from ros2course import sandbox

#: Our own node is hidden (leading underscore), so "nodes seen" lists stay the learner's.
GRADER_NODE = "_ros2course_grader"
#: Seconds a reliable sample may be late: a DDS sample lost on a loaded machine is repaired
#: after the writer's next heartbeat (Fast DDS's default heartbeat period is 3 s) and holds
#: back the samples behind it. Graders wait this long only while messages are missing.
LATE_DELIVERY = 3.5


@dataclasses.dataclass(frozen=True)
class RateStats:
    """Message rate computed the way ``ros2 topic hz`` does (ros2topic/verb/hz.py).

    Attributes:
        rate_hz: 1 / mean of the deltas between consecutive arrivals, Hz.
        mean_period: mean delta, seconds.
        min_period, max_period: extreme deltas, seconds.
        std_dev: population standard deviation of the deltas, seconds.
        samples: number of deltas (messages - 1, the missed ones included).
        missed: messages the reader never got between its first and last, known from the
            publisher's sequence numbers (0 when none were given).
        median_period: median delta, seconds (0.0 when built by hand).
    """

    rate_hz: float
    mean_period: float
    min_period: float
    max_period: float
    std_dev: float
    samples: int
    missed: int = 0
    median_period: float = 0.0

    @classmethod
    def from_times(cls, times: list[float], sequence: list[int | None] | None = None) -> RateStats | None:
        """Stats over arrival (or stamp) times in seconds; None with fewer than 2 times.

        ``sequence``: each message's publication sequence number (``rmw_message_info_t``'s
        ``publication_sequence_number``, which rclpy passes a subscription callback as
        ``publication_sequence_number``), used only when every one is given and they increase (one
        writer). A gap of k numbers between two messages then counts as k intervals of delta / k: a
        message the reader lost on a loaded machine (a best-effort reader, a full shared-memory
        port) does not lengthen the publisher's measured period.
        """
        if len(times) < 2:
            return None
        counted = (sequence is not None and len(sequence) == len(times) and None not in sequence
                   and all(b > a for a, b in zip(sequence, sequence[1:])))
        steps = [b - a for a, b in zip(sequence, sequence[1:])] if counted else [1] * (len(times) - 1)
        deltas = [(b - a) / k for a, b, k in zip(times, times[1:], steps) for _ in range(k)]
        mean = sum(deltas) / len(deltas)
        return cls(1.0 / mean if mean > 0 else float("inf"), mean, min(deltas), max(deltas),
                   statistics.pstdev(deltas), len(deltas), len(deltas) - (len(times) - 1),
                   statistics.median(deltas))

    def within(self, expected_hz: float, tolerance: float, *, median: bool = False) -> bool:
        """True when the mean period (the median with ``median``) is within ``tolerance`` (fraction, e.g. 0.15)
        of 1/expected_hz."""
        expected_period = 1.0 / expected_hz
        period = self.median_period if median else self.mean_period
        return abs(period - expected_period) <= tolerance * expected_period

    def describe(self) -> str:
        """Human summary, e.g. ``2.00 Hz (mean period 0.500 s, min 0.498, max 0.502, 6 intervals)``;
        periods under 0.1 s in milliseconds (``500.0 Hz (mean period 2.00 ms, min 1.95, max 2.10, ...)``);
        messages the reader missed are counted after the intervals."""
        missed = (f", {self.missed} message(s) the grader's reader missed counted by the publisher's sequence "
                  "numbers" if self.missed else "")
        if self.mean_period < 0.1:
            return (f"{self.rate_hz:.1f} Hz (mean period {self.mean_period * 1000:.2f} ms, min "
                    f"{self.min_period * 1000:.2f}, max {self.max_period * 1000:.2f}, {self.samples} intervals"
                    f"{missed})")
        return (f"{self.rate_hz:.2f} Hz (mean period {self.mean_period:.3f} s, min {self.min_period:.3f}, "
                f"max {self.max_period:.3f}, {self.samples} intervals{missed})")


def wait_until(predicate: Callable[[], bool], timeout: float, interval: float = 0.02,
               abort: Callable[[], bool] | None = None) -> bool:
    """Poll ``predicate`` until true, ``timeout`` seconds pass, or ``abort()`` is true."""
    deadline = time.monotonic() + timeout
    while True:
        if predicate():
            return True
        if time.monotonic() >= deadline or (abort is not None and abort()):
            return predicate()
        time.sleep(interval)


def _domain_selector() -> Callable[[], int]:
    # domain_coordinator's default selector starts at 1 every time; a random
    # start makes concurrent checks collide less often (both are safe anyway).
    start = random.randrange(100)
    state = {"n": start}

    def select() -> int:
        value = (state["n"] % 100) + 1
        state["n"] += 1
        return value

    return select


def discovery_range() -> str:
    """``ROS_AUTOMATIC_DISCOVERY_RANGE`` for the grader and learner nodes: ``LOCALHOST`` (REP 2009, Jazzy).

    Batch grading under a submission uid sets ``ROS2COURSE_DISCOVERY_RANGE=SUBNET``:
    rmw_fastrtps's LOCALHOST mode forces Fast DDS's shared-memory transport,
    whose segments a grader and a node of two different users cannot both
    write; the job's network namespace has only loopback, so its "subnet" is
    the namespace itself (see :mod:`ros2course.sandbox`).
    """
    return os.environ.get("ROS2COURSE_DISCOVERY_RANGE", "LOCALHOST")


_DISCOVERY_LOCK = threading.Lock()

#: Fast DDS reads a process's XML profiles from this variable once, at its first participant (Fast DDS 2.14,
#: the version Jazzy's rmw_fastrtps_cpp uses; ``FASTDDS_DEFAULT_PROFILES_FILE`` is 3.x's name).
PROFILES_VARIABLE = "FASTRTPS_DEFAULT_PROFILES_FILE"
#: Seconds between the grader's participant announcements (Fast DDS ``leaseAnnouncement``; its default is 3 s).
#: A participant that joins announces itself a few times at once, and an existing one answers it; on a
#: loaded machine that first exchange is sometimes missed, and the two then met only at the grader's next
#: announcement, up to 3 s later: a ``ros2 service list --spin-time 2`` ended before it saw the grader's
#: long-standing nodes in 1 run in 3 with two busy cores (measured with a bare rclpy observer and
#: ``yes`` loads, issue 37's inspect-services ``listed_late``); announcing every 0.25 s, 0 in 8.
GRADER_ANNOUNCEMENT_PERIOD = 0.25


@dataclasses.dataclass
class _ProfileChoice:
    """This process's Fast DDS profile decision, made once (at its first ROS context, :func:`_use_grader_profile`).

    Attributes:
        made: whether it was made.
        learners: the profile file learner processes keep (None: none): the grader's own never reaches them.
    """

    made: bool = False
    learners: str | None = None


_profile_choice = _ProfileChoice()


def grader_profile_xml() -> str:
    """The Fast DDS XML profile of the grader's participants: announce every :data:`GRADER_ANNOUNCEMENT_PERIOD`
    seconds, over UDP only when a batch job asks for it (``ROS2COURSE_DISCOVERY_RANGE=SUBNET``, the
    transport of :data:`ros2course.sandbox.FASTDDS_UDP_ONLY`, which the job's learner processes keep)."""
    return sandbox.fastdds_profile_xml("ros2course_grader", udp_only=discovery_range() == "SUBNET",
                                       announcement_period=GRADER_ANNOUNCEMENT_PERIOD,
                                       comment="ros2course: the grader's own participants "
                                               "(ros2course.run.probes.configure_process_discovery)")


def _use_grader_profile() -> None:
    """Point this process's Fast DDS at :func:`grader_profile_xml` (a file in the cache folder, named by its
    content), unless a profile of the user's own is set (theirs wins: a DDS setup of their machine), and
    remember what learner processes keep. Called with :data:`_DISCOVERY_LOCK` held."""
    if _profile_choice.made:
        return
    inherited = os.environ.get(PROFILES_VARIABLE)
    _profile_choice.made, _profile_choice.learners = True, inherited
    from ros2course.files import cache_dir  # noqa: PLC0415 - platformdirs only when grading

    if inherited and discovery_range() != "SUBNET":
        return  # the user's own profile; a batch job's (UDP only) is rewritten with the announcements
    text = grader_profile_xml()
    path = cache_dir() / f"fastdds-grader-{hashlib.sha256(text.encode()).hexdigest()[:12]}.xml"
    try:
        if not path.is_file():
            path.parent.mkdir(parents=True, exist_ok=True)
            temporary = path.with_name(f"{path.name}.{os.getpid()}.tmp")
            temporary.write_text(text, encoding="utf-8")
            temporary.replace(path)
    except OSError as error:  # a read-only cache folder: Fast DDS's defaults, discovery only slower under load
        logging.getLogger(__name__).warning("the grader's Fast DDS profile could not be written (%s): "
                                            "its participants announce themselves every 3 s", error)
        return
    os.environ[PROFILES_VARIABLE] = str(path)


def learner_profile_env(env: dict[str, str]) -> dict[str, str]:
    """``env`` with the grader's own Fast DDS profile (:func:`grader_profile_xml`) replaced by the one the
    process inherited (or none): learner nodes run with Fast DDS's defaults, or the user's or batch job's
    profile, as in the learner's terminal."""
    ours = os.environ.get(PROFILES_VARIABLE) if _profile_choice.made else None
    if ours is not None and env.get(PROFILES_VARIABLE) == ours != _profile_choice.learners:
        if _profile_choice.learners is None:
            env.pop(PROFILES_VARIABLE)
        else:
            env[PROFILES_VARIABLE] = _profile_choice.learners
    return env


def configure_process_discovery() -> None:
    """Give this process's own ROS contexts the discovery range of :func:`discovery_range`.

    The one environment variable grading sets in its own process, and why: rcl
    reads ``ROS_AUTOMATIC_DISCOVERY_RANGE`` only from the process environment,
    in ``rcl_init`` (rcl/src/rcl/discovery_options.c), and rclpy's ``init`` has no
    parameter for it. The value is a constant of the process (never swapped per
    check or per thread, unlike the removed ``patched_environ``), so contexts
    created on several threads at once all read the same value. Learner
    processes get theirs explicitly (:meth:`RosSession.learner_env`).
    """
    value = discovery_range()
    with _DISCOVERY_LOCK:
        if os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE") != value:
            os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = value
        os.environ.pop("ROS_LOCALHOST_ONLY", None)  # deprecated in Jazzy; it would override the range
        _use_grader_profile()


def spin_until_shutdown(executor: Any) -> None:
    """Run ``executor.spin()`` on the calling thread until the executor or its context is shut down.

    Every way rclpy (Jazzy 7.1) ends a spin at shutdown is expected here and ends it quietly:
    ``ExternalShutdownException`` (the context was shut down), ``RuntimeError`` (an entity destroyed
    under the wait) and ``AttributeError``: ``Executor.shutdown`` sets its guard conditions to None
    (rclpy ``executors.py``, ``shutdown``) while this thread may be building its next wait set from
    them, which then reads ``None.handle`` (seen in a check with three graphs). Any other exception
    is a bug and propagates.

    A ``RuntimeError`` while the executor and its context still run is an
    entity destroyed under the wait from another thread (a probe closed while
    this thread waits on it: rclpy's ``InvalidHandle``); it ends that wait
    only and the spin goes on (at most ``MAX_SPIN_ERRORS`` times), so the
    graph's other probes keep receiving. rclpy (Jazzy 7.1) has no public
    "was shut down" on an executor: ``_is_shutdown`` is read, and its absence
    means "shut down" (the old behaviour: end the spin).
    """
    from rclpy.executors import ExternalShutdownException  # noqa: PLC0415 - rclpy only when grading (list/show stay light)

    for _ in range(MAX_SPIN_ERRORS + 1):
        try:
            executor.spin()
            return
        except ExternalShutdownException:
            return
        except AttributeError:
            return
        except RuntimeError:
            if getattr(executor, "_is_shutdown", True) or not executor.context.ok():
                return


#: Errors :func:`spin_until_shutdown` lets one spin survive (entities destroyed under its wait).
MAX_SPIN_ERRORS = 100


def stop_spinning(executor: Any, thread: threading.Thread, timeout: float = 5.0) -> bool:
    """Shut down ``executor`` and wait for ``thread``, which spins it, to leave; True when it has.

    A node must never be destroyed while a thread may still be inside the
    executor's ``wait`` on it: rclpy (Jazzy 7.1) then crashes the whole process
    (a segfault in ``event_handler.__exit__``, seen in CI under load, and a
    pytest worker lost in ``inspect-services``). ``Executor.shutdown`` does not
    wait for the spin loop to leave (rclpy ``executors.py``: it only triggers the
    guard condition), so the join here is what makes destroying safe. Every
    grader-side node spun on a thread of its own (the session's probe node,
    :class:`ros2course.kit.mystery.MysteryNode`, a lesson's probe) stops this way.

    Args:
        executor: an ``rclpy.executors.Executor`` (None when it was never made).
        thread: the thread running ``executor.spin()``.
        timeout: seconds to wait for the thread.
    """
    if executor is not None:
        with contextlib.suppress(Exception):
            executor.shutdown(timeout_sec=timeout)
    thread.join(timeout)
    return not thread.is_alive()


#: Held while rclpy is first imported (:func:`import_rclpy`): two threads importing it at once can deadlock
#: on importlib's module locks (CPython raises ``_DeadlockError``; seen when two parts of a check opened
#: their graphs together, kit.parts.at_once).
_IMPORTING = threading.Lock()


def import_rclpy() -> None:
    """Import what a :class:`RosSession` uses of rclpy, one thread at a time.

    Call it on the main thread before starting threads that may open a graph
    (:func:`ros2course.kit.parts.at_once` does); :meth:`RosSession.node` calls it too.
    """
    with _IMPORTING:
        import rclpy  # noqa: F401, PLC0415 - rclpy only when grading
        import rclpy.executors  # noqa: F401, PLC0415 - rclpy only when grading
        import rclpy.node  # noqa: F401, PLC0415 - rclpy only when grading
        import rclpy.parameter  # noqa: F401, PLC0415 - rclpy only when grading
        import rclpy.qos  # noqa: F401, PLC0415 - rclpy only when grading
        import rclpy.signals  # noqa: F401, PLC0415 - rclpy only when grading


class RosSession:
    """One check's private ROS graph.

    Use as a context manager. Entering only holds a domain id (no rclpy yet); the grader's
    own participant (rclpy context, node, executor thread: ~0.07 s with rclpy's import) opens
    on first use of :attr:`node` or :attr:`context`, so a check whose first step starts a
    learner's node boots that node on the other core meanwhile (issue 36). Attributes once entered:
        domain_id: the ``ROS_DOMAIN_ID`` held for this session (1-100).
        context: the rclpy ``Context`` (opens the participant).
        node: the hidden grader node (opens the participant).
        peers_started: how many environments :meth:`learner_env` gave out (processes that may have
            joined this graph; 0 means no node but the grader's was ever in it).
        recorder: where its probes write what they observe (:class:`~ros2course.run.recording.Recorder`), or None.
        heard: topic -> ``time.monotonic()`` of the last message a probe of this session received on it
            (kept by :func:`record`, with or without a recorder; the ``silent`` diagnosis reads it).
        matched: topic -> ``time.monotonic()`` since when a :class:`TopicProbe` on it has had a matched
            publisher (rmw's ``matched`` event, ``current_count`` > 0); removed when none is left.

    Args:
        recorder: see the attribute.
        domain_holder: an ``ExitStack`` that holds the domain id instead of the session, released
            when the caller closes it (default: released when the session closes). A check holds
            its domains until its learner processes are stopped: a ``ros2`` daemon of the check
            (XML-RPC on port 11511 + domain id) outlives the check's graph, and another check that
            took the domain meanwhile would find it "already running" and then lose it (CI: an
            inspect-topics reference printed "Unknown topic", its daemon killed under it).

    Raises:
        RuntimeError: from ``domain_coordinator`` when no domain id is free.
    """

    def __init__(self, recorder: Any = None, domain_holder: contextlib.ExitStack | None = None) -> None:
        self.recorder = recorder
        self._domain_holder = domain_holder
        self.heard: dict[str, float] = {}
        self.matched: dict[str, float] = {}
        self.domain_id = -1
        self.peers_started = 0
        self._stack = contextlib.ExitStack()
        self._context = None
        self._node = None
        self._executor = None
        self._thread: threading.Thread | None = None
        self._opening = threading.Lock()
        self._closed = False

    def learner_env(self, base: dict[str, str]) -> dict[str, str]:
        """``base`` plus this session's domain id and localhost-only discovery."""
        self.peers_started += 1
        env = dict(base)
        env["ROS_DOMAIN_ID"] = str(self.domain_id)
        env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = discovery_range()
        env.pop("ROS_LOCALHOST_ONLY", None)  # deprecated in Jazzy, prints a warning
        learner_profile_env(env)
        env.setdefault("RCUTILS_LOGGING_BUFFERED_STREAM", "1")
        env["PYTHONUNBUFFERED"] = "1"
        return env

    def __enter__(self) -> RosSession:
        # ROS imports stay lazy: list/hint must not pay for them
        import domain_coordinator  # noqa: PLC0415 - only when grading

        try:
            holder = self._stack if self._domain_holder is None else self._domain_holder
            self.domain_id = holder.enter_context(domain_coordinator.domain_id(_domain_selector()))
            configure_process_discovery()
        except BaseException:
            self._stack.close()
            raise
        return self

    @property
    def node(self) -> Any:
        """The hidden grader node (``rclpy.node.Node``); opens the participant on first use."""
        return self._open()

    @property
    def context(self) -> Any:
        """The session's rclpy ``Context``; opens the participant on first use."""
        self._open()
        return self._context

    @property
    def opened(self) -> bool:
        """Whether the grader's participant is open (:attr:`node` was used)."""
        return self._node is not None

    def _open(self) -> Any:
        """Open the grader's participant once (any thread): rclpy context in this domain, node, executor.

        Raises:
            RuntimeError: the session is not entered, or already closed.
        """
        if self._node is not None:
            return self._node
        with self._opening:
            if self._node is not None:
                return self._node
            if self.domain_id < 0 or self._closed:
                raise RuntimeError("RosSession used outside its 'with' block")
            import_rclpy()
            import rclpy  # noqa: PLC0415 - rclpy only when grading
            from rclpy.executors import MultiThreadedExecutor  # noqa: PLC0415 - rclpy only when grading
            from rclpy.parameter import Parameter  # noqa: PLC0415 - rclpy only when grading
            from rclpy.signals import SignalHandlerOptions  # noqa: PLC0415 - rclpy only when grading

            self._context = rclpy.Context()
            rclpy.init(context=self._context, domain_id=self.domain_id,
                       signal_handler_options=SignalHandlerOptions.NO)
            self._stack.callback(self._shutdown_context)
            # The grader's node needs no type description service (saves ~70 ms per check).
            node = rclpy.create_node(
                GRADER_NODE, context=self._context, enable_rosout=False, start_parameter_services=False,
                parameter_overrides=[Parameter("start_type_description_service", value=False)])
            # Two threads: a stand-in action server's goal runs for seconds while a cancel is answered. The cost:
            # while a callback of the node's default (mutually exclusive) group runs, rclpy's MultiThreadedExecutor
            # finds the group's next ready entity again at once and loops (benchmarks/executor_load.py: a 500 Hz
            # topic took a core and lost most messages; 20 Hz, the fastest a lesson probes here, 5 % of a core
            # against 2 % single-threaded, none lost). Faster streams get a probe with an executor of its own.
            self._executor = MultiThreadedExecutor(num_threads=2, context=self._context)
            self._executor.add_node(node)
            self._thread = threading.Thread(target=self._spin, daemon=True, name="ros2course-executor")
            self._thread.start()
            self._node = node
        return node

    def _spin(self) -> None:
        spin_until_shutdown(self._executor)

    def _shutdown_context(self) -> None:
        """Stop the executor thread first (:func:`stop_spinning`), then destroy the node and the context.

        Shutting the context down is what rclpy's own Ctrl+C does to a spinning
        executor, so it is the second way out; a thread that still has not left
        is left with its node (a daemon thread: a leak for this process, never a crash).
        """
        import rclpy  # noqa: PLC0415 - rclpy only when grading (list/show stay light)

        stopped = self._thread is None or stop_spinning(self._executor, self._thread)
        if not stopped:
            with contextlib.suppress(Exception):
                rclpy.shutdown(context=self._context)
            self._thread.join(timeout=3.0)
            stopped = not self._thread.is_alive()
        if self._node is not None and stopped:
            self._node.destroy_node()
        with contextlib.suppress(Exception):
            rclpy.shutdown(context=self._context)

    def __exit__(self, *exc: Any) -> None:
        with self._opening:
            self._closed = True
        self._stack.close()

    # --- graph ---------------------------------------------------------------

    def node_names(self) -> list[str]:
        """Fully qualified names of the nodes in the graph, our own hidden node excluded."""
        names = []
        for name, namespace in self.node.get_node_names_and_namespaces():
            if name.startswith("_"):
                continue
            names.append(f"{namespace.rstrip('/')}/{name}")
        return sorted(names)

    def wait_for_node(self, name: str, timeout: float, abort: Callable[[], bool] | None = None) -> bool:
        """Wait until a node called ``name`` (``"print_forever"`` or ``"/ns/name"``) is in the graph."""
        wanted = name if name.startswith("/") else f"/{name}"
        return wait_until(lambda: wanted in self.node_names(), timeout, interval=0.05, abort=abort)

    def topic_types(self) -> dict[str, list[str]]:
        """Every topic in the graph and its type names, e.g. ``{"/chatter": ["std_msgs/msg/String"]}``."""
        return dict(self.node.get_topic_names_and_types())

    # --- probes ------------------------------------------------------------

    def topic(self, topic: str, msg_type: type, qos: Any = 10) -> TopicProbe:
        """Subscribe to ``topic`` and record every message with its arrival time and send stamp."""
        return TopicProbe(self, topic, msg_type, qos)

    def rosout(self) -> RosoutProbe:
        """Record every ``/rosout`` log record (transient-local: earlier records are replayed)."""
        return RosoutProbe(self)


class TopicProbe:
    """Messages received on one topic, with arrival time and the publisher's send stamp.

    Every message is recorded with its arrival time (``time.monotonic()``
    when the grader's callback ran, seconds) and its DDS source timestamp
    (when the publisher wrote it: the wall clock in the publisher's process,
    seconds). The subscription callback takes two arguments, so rclpy
    (Jazzy) hands it the ``MessageInfo`` holding ``source_timestamp``.

    Rates are computed over the send stamps with the formula of ``ros2 topic
    hz`` (1 / mean delta, ros2topic/verb/hz.py). ``ros2 topic hz`` itself
    uses arrival times, but on a loaded 2-core machine the grader's thread
    may get the CPU late and receive two messages at once (CI saw a correct
    2 Hz timer measured at 3.2 Hz on arrivals: min delta 0.000 s); the send
    stamps judge the learner's timer, not the machine's scheduling.

    For topics up to a few tens of Hz: its callback runs on the session's multi-threaded executor, which
    busy-loops on a fast topic (``benchmarks/executor_load.py``: at 100 Hz 60 % of a core and a sixth of the
    messages lost). A faster stream needs a probe with a single-threaded executor of its own
    (``graders/_joint_stream.py``, 500 Hz).
    """

    def __init__(self, session: RosSession, topic: str, msg_type: type, qos: Any = 10) -> None:
        self.topic = topic
        self._session = session
        self._lock = threading.Lock()
        self._samples: list[tuple[float, float, Any]] = []
        self._sequence: list[int | None] = []  # the publisher's publication sequence number per sample
        self._matched_at: float | None = None  # time.monotonic() since this subscription has had a publisher
        from rclpy.event_handler import SubscriptionEventCallbacks  # noqa: PLC0415 - rclpy only when grading

        # DDS's own "matched" event (a publisher of the same type with compatible QoS connected):
        # when it happened is what the engine's ``silent`` diagnosis needs (ros2course.run.diagnose)
        self._sub = session.node.create_subscription(msg_type, topic, self._on_message, qos,
                                                     event_callbacks=SubscriptionEventCallbacks(matched=self._on_matched))

    def _on_matched(self, status: Any) -> None:
        """Keep :meth:`matched_since` and :attr:`RosSession.matched`: since when this subscription (and a
        probe of the session on its topic) has had a matched publisher."""
        if status.current_count > 0:
            now = time.monotonic()
            if self._matched_at is None:
                self._matched_at = now
            self._session.matched.setdefault(self.topic, now)
        else:
            self._matched_at = None
            self._session.matched.pop(self.topic, None)

    def matched_since(self) -> float | None:
        """``time.monotonic()`` seconds since when this subscription has had a matched publisher (DDS's
        ``matched`` event: a publisher of the type with compatible QoS connected), or None while it has none.

        What a publisher wrote before that moment never reached this probe (VOLATILE durability), so a
        window judging what a node writes starts no earlier than this.
        """
        return self._matched_at

    def _on_message(self, msg: Any, info: Any) -> None:
        now = time.monotonic()
        # rclpy passes MessageInfo as a dict of rmw_message_info_t fields (nanoseconds).
        stamp = info.get("source_timestamp", 0) * 1e-9 if isinstance(info, dict) else 0.0
        sequence = info.get("publication_sequence_number") if isinstance(info, dict) else None
        with self._lock:
            self._samples.append((now, stamp or time.time(), msg))
            self._sequence.append(sequence or None)  # 0: the middleware does not say
        record(self._session, self.topic, msg, int(stamp * 1e9) if stamp else None)

    def samples(self) -> list[tuple[float, Any]]:
        """(arrival time, message) pairs so far, oldest first."""
        with self._lock:
            return [(arrival, msg) for arrival, _, msg in self._samples]

    def send_stamps(self, count: int | None = None) -> list[float]:
        """The publisher's send stamps (seconds) of the first ``count`` messages (all when None)."""
        with self._lock:
            stamps = [stamp for _, stamp, _ in self._samples]
        return stamps[:count] if count else stamps

    def sequence_numbers(self) -> list[int | None]:
        """Per message so far, oldest first, its publication sequence number: the writer's count of what it had
        written, 1 for its first message (rmw_message_info_t.publication_sequence_number; Fast DDS numbers each
        writer's samples from 1), or None where the middleware gives none. A first message heard with number
        k means k - 1 were written before it, sent before this subscription matched the publisher (lost: a
        VOLATILE publisher keeps nothing for late subscriptions)."""
        with self._lock:
            return list(self._sequence)

    def messages(self) -> list[Any]:
        """Messages so far, oldest first."""
        return [msg for _, msg in self.samples()]

    def wait_for_count(self, count: int, timeout: float, abort: Callable[[], bool] | None = None) -> bool:
        """Wait until ``count`` messages arrived (or ``timeout`` seconds)."""
        return wait_until(lambda: len(self._samples) >= count, timeout, abort=abort)

    def observe(self, count: int, period: float, start_timeout: float,
                abort: Callable[[], bool] | None = None) -> float:
        """Wait for a stream of ``count`` messages expected every ``period`` seconds; returns seconds waited.

        The window is counted from the first message, not from when the
        wait began: a node that took long to start on a loaded machine
        still gets ``count * period`` seconds, plus :data:`LATE_DELIVERY`
        for a sample that DDS must repair. The first message may take up to
        ``start_timeout`` seconds. Waiting longer never changes a verdict
        (rates use the send stamps); it only costs time while messages are
        missing, and returns as soon as ``count`` arrived.
        """
        begin = time.monotonic()
        if not wait_until(lambda: bool(self._samples), start_timeout, abort=abort):
            return time.monotonic() - begin
        with self._lock:
            first = self._samples[0][0]
        remaining = first + count * period + LATE_DELIVERY - time.monotonic()
        self.wait_for_count(count, max(0.0, remaining), abort=abort)
        return time.monotonic() - begin

    def sent_after(self, wall_time: float) -> list[Any]:
        """Messages the publisher sent after ``wall_time`` (``time.time()`` seconds), by their send stamps.

        "After a parameter change" must be judged where the message was
        written: a message sent before the change can arrive after it on a
        loaded machine (CI saw the old quote "after" a change on arrival times).
        """
        with self._lock:
            return [msg for _, stamp, msg in self._samples if stamp > wall_time]

    def wait_sent_after(self, wall_time: float, count: int, period: float,
                        abort: Callable[[], bool] | None = None) -> list[Any]:
        """Wait up to ``count * period + LATE_DELIVERY`` s for ``count`` messages sent after ``wall_time``."""
        wait_until(lambda: len(self.sent_after(wall_time)) >= count, count * period + LATE_DELIVERY, abort=abort)
        return self.sent_after(wall_time)

    def rate(self, count: int | None = None) -> RateStats | None:
        """Rate over the send stamps of the first ``count`` messages (``ros2 topic hz``'s formula)."""
        return RateStats.from_times(self.send_stamps(count))

    def arrival_rate(self) -> RateStats | None:
        """Rate over arrival times, exactly what ``ros2 topic hz`` would print (for diagnostics)."""
        return RateStats.from_times([t for t, _ in self.samples()])


class RosoutProbe(TopicProbe):
    """Log records on ``/rosout`` (``rcl_interfaces/msg/Log``).

    The subscription uses rcl's rosout QoS (reliable, transient local, depth
    1000), so records a node logged before the probe matched are replayed.
    """

    def __init__(self, session: RosSession) -> None:
        from rcl_interfaces.msg import Log  # noqa: PLC0415 - rclpy only when grading (list/show stay light)
        from rclpy.qos import (  # noqa: PLC0415 - rclpy only when grading
            DurabilityPolicy,
            HistoryPolicy,
            QoSProfile,
            ReliabilityPolicy,
        )

        qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
        super().__init__(session, "/rosout", Log, qos)

    def records(self, node: str | None = None, level: int | None = None,
                match: Callable[[str], bool] | None = None) -> list[Any]:
        """Log records, optionally only from logger ``node``, at ``level``, whose text passes ``match``."""
        out = []
        for msg in self.messages():
            if node is not None and msg.name != node:
                continue
            if level is not None and msg.level != level:
                continue
            if match is not None and not match(msg.msg):
                continue
            out.append(msg)
        return out

    def loggers(self) -> list[str]:
        """Names of every logger that logged so far, sorted."""
        return sorted({msg.name for msg in self.messages()})


def record(session: RosSession, topic: str, msg: Any, publish_ns: int | None = None) -> None:
    """Note that ``msg`` arrived (:attr:`RosSession.heard`) and write it into the session's recording, if it
    has one (never raises: a recording cannot fail a check).

    Args:
        topic: the channel name (a topic, or ``<service>/request`` / ``<service>/response``).
        publish_ns: the publisher's send stamp in ns since the epoch (default: now).
    """
    session.heard[topic] = time.monotonic()
    if session.recorder is None:
        return
    try:
        session.recorder.write(session.domain_id, topic, msg, publish_ns)
    except Exception:  # noqa: BLE001 - the evidence is best effort, the verdict is not
        logging.getLogger(__name__).debug("recording %s failed", topic, exc_info=True)


def stamp_seconds(stamp: Any) -> float:
    """A ``builtin_interfaces/Time`` as float seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


def wait_future(future: Any, timeout: float) -> Any:
    """Wait for an rclpy ``Future`` completed by the session's executor thread.

    Returns:
        the future's result.

    Raises:
        TimeoutError: not done within ``timeout`` seconds.
    """
    if not wait_until(future.done, timeout, interval=0.005):
        future.cancel()
        raise TimeoutError(f"no answer within {timeout:.1f} s")
    return future.result()


@contextlib.contextmanager
def parameter_client(session: RosSession, node_name: str, timeout: float = 5.0) -> Iterator[Any]:
    """An ``rclpy.parameter_client.AsyncParameterClient`` for ``node_name`` once its services are up.

    Raises:
        TimeoutError: the node's parameter services did not appear within ``timeout`` s.
    """
    from rclpy.parameter_client import AsyncParameterClient  # noqa: PLC0415 - rclpy only when grading (list/show stay light)

    # AsyncParameterClient has no destroy(); its clients go with the session's node.
    client = AsyncParameterClient(session.node, node_name)
    if not wait_until(client.services_are_ready, timeout, interval=0.05):
        raise TimeoutError(f"parameter services of {node_name} not available within {timeout:.1f} s")
    yield client


def call_service(session: RosSession, srv_type: type, name: str, request: Any,
                 timeout: float = 5.0) -> Any:
    """Call service ``name`` once and return the response.

    Args:
        srv_type: the generated service class (e.g. ``WhatIsThePoint``).
        request: a ``srv_type.Request`` instance.
        timeout: seconds for the service to appear plus seconds for the answer.

    Raises:
        TimeoutError: the service did not appear, or did not answer in time.
    """
    client = session.node.create_client(srv_type, name)
    try:
        if not client.wait_for_service(timeout_sec=timeout):
            raise TimeoutError(f"service {name} not available within {timeout:.1f} s")
        record(session, f"{name}/request", request)
        response = wait_future(client.call_async(request), timeout)
        record(session, f"{name}/response", response)
        return response
    finally:
        session.node.destroy_client(client)
