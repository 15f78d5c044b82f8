"""Grader for ``lifecycle-node`` (a managed node; contract in chapters/lifecycle-node/CONTRACT.md).

Black-box, as ``ros2 lifecycle`` would drive it: the grader calls the node's
``/<node>/change_state`` and ``/<node>/get_state`` services (lifecycle_msgs)
with its own client and judges, state by state, what the node sends on
``/heartbeat``. The sequence is the managed-node state machine of
design.ros2.org/articles/node_lifecycle.html::

    unconfigured -configure-> inactive -activate-> active -deactivate-> inactive
    -cleanup-> unconfigured -configure-> inactive -activate-> active -shutdown-> finalized, then Ctrl+C

and two more runs, each in a graph of its own: shutdown straight from unconfigured, and configure then
shutdown from inactive (the state machine's other two shutdowns).

"Nothing while X" is judged on the messages' send stamps (written while the
node was in X, whenever they arrive), rates on send stamps too; a quiet
window ends early on the first message sent in it.
"""

from __future__ import annotations

import itertools
import re
import time
from typing import Any

from ros2course import kit
from ros2course.kit import Check, GradingSession, Unmet, call_service, checks, wait_until
from ros2course.kit.nodes import StartedNode
from ros2course.kit import topics_services as ts

from . import _services

PACKAGE = "python_package_with_a_lifecycle_node"
EXECUTABLE = "lifecycle_heartbeat_node"
NODE = "lifecycle_heartbeat"
TOPIC = "/heartbeat"
TOPIC_TYPE = "std_msgs/msg/String"
PERIOD = 0.2  # seconds between heartbeats while active (5 Hz; CONTRACT.md)
SAMPLES = 6  # messages per active window -> 5 intervals (shared/LESSONS.md minimum)
#: Seconds each inactive state is watched for a message: 3 periods, so a node that ignores its
#: state sends about 3 (a quiet window ends at the first one sent in it; a correct node costs
#: the whole window, four times per check).
QUIET = 3 * PERIOD
#: Seconds for a transition's answer (the learner's callback runs inside the service call).
ANSWER_TIMEOUT = 3.0
#: Seconds for the node's publisher to leave the graph after cleanup (DDS announces a
#: destroyed endpoint at once; a loaded machine may take a few hundred ms to tell us).
GONE_TIMEOUT = 2.0
#: What each message says (the lesson: 'Heartbeat 0', 'Heartbeat 1', ...); the first number seen is not judged:
#: the timer runs (and counts) while the node is inactive, its messages dropped by the lifecycle publisher.
HEARTBEAT = re.compile(r"Heartbeat (-?\d+)")
#: lifecycle_msgs/msg/State primary state ids (lifecycle_msgs/msg/State.msg).
UNCONFIGURED, INACTIVE, ACTIVE, FINALIZED = 1, 2, 3, 4
STATE_LABELS = {0: "unknown", UNCONFIGURED: "unconfigured", INACTIVE: "inactive", ACTIVE: "active",
                FINALIZED: "finalized"}
#: lifecycle_msgs/msg/Transition ids, by the label ``ros2 lifecycle set`` takes (Transition.msg);
#: shutdown has one id per primary state it leaves.
CONFIGURE, CLEANUP, ACTIVATE, DEACTIVATE = 1, 2, 3, 4
SHUTDOWN_FROM = {UNCONFIGURED: 5, INACTIVE: 6, ACTIVE: 7}

#: Seconds of observation the contract needs: four quiet windows and two active ones.
WINDOW = 4 * QUIET + 2 * SAMPLES * PERIOD

RUN = ("executable",)
CHECKS = [
    Check("build", "The package builds with colcon", 1),
    *checks.started("", PACKAGE, EXECUTABLE, NODE),
    Check("managed", f"It is a managed node: /{NODE}/get_state answers 'unconfigured' at start", 2,
          "subclass rclpy.lifecycle.LifecycleNode (from rclpy.lifecycle import LifecycleNode), not rclpy.node.Node: "
          "only a LifecycleNode offers the change_state/get_state services ros2 lifecycle uses", needs=RUN),
    Check("quiet_unconfigured", f"Nothing is published on {TOPIC} while unconfigured", 1,
          "create nothing in __init__: the publisher and the timer belong in on_configure", needs=("managed",)),
    Check("configure", "configure succeeds: unconfigured -> inactive", 2,
          "on_configure creates the lifecycle publisher and the timer and returns TransitionCallbackReturn.SUCCESS",
          needs=("managed",)),
    Check("quiet_inactive", f"Nothing is published on {TOPIC} while inactive", 2,
          "create the publisher with self.create_lifecycle_publisher(String, 'heartbeat', 10): its publish() drops "
          "messages until the node is activated (a plain create_publisher() publishes in every state)",
          needs=("configure",)),
    Check("activate", "activate succeeds: inactive -> active", 1,
          "on_activate returns super().on_activate(state) (TransitionCallbackReturn.SUCCESS)", needs=("configure",)),
    Check("active_messages", f"While active it publishes {TOPIC_TYPE} 'Heartbeat N' on {TOPIC}, N counting up", 2,
          "return super().on_activate(state) from on_activate: the base class is what enables the lifecycle "
          "publisher", needs=("activate",)),
    Check("active_rate", f"While active it publishes every {PERIOD} s ({1 / PERIOD:.0f} Hz)", 2,
          f"create the timer in on_configure with self.create_timer({PERIOD}, self.timer_callback)",
          needs=("active_messages",)),
    Check("deactivate", "deactivate succeeds: active -> inactive", 1,
          "on_deactivate must return a TransitionCallbackReturn: return super().on_deactivate(state)",
          needs=("activate",)),
    Check("quiet_deactivated", f"Nothing is published on {TOPIC} after deactivate", 2,
          "return super().on_deactivate(state) from on_deactivate: the base class disables the lifecycle publisher",
          needs=("deactivate",)),
    Check("cleanup", f"cleanup succeeds (inactive -> unconfigured) and the node's {TOPIC} publisher is gone", 2,
          "in on_cleanup destroy what on_configure created: self.destroy_timer(self.timer) and "
          "self.destroy_lifecycle_publisher(self.heartbeat_publisher)", needs=("deactivate",)),
    Check("reconfigure", f"After cleanup, configure and activate work again: one heartbeat every {PERIOD} s", 2,
          "on_cleanup must leave the node as __init__ did: a timer that survives cleanup keeps firing beside the "
          "one the next on_configure creates", needs=("cleanup",)),
    Check("shutdown", f"shutdown from active reaches finalized, and nothing is published on {TOPIC} after it", 2,
          "in on_shutdown destroy the timer and the publisher (shutdown may come while active: the base class does "
          "not deactivate the publisher) and return TransitionCallbackReturn.SUCCESS", needs=("managed",)),
    checks.ctrl_c("sigint_exit", "the finalized node", 1, needs=RUN),
    Check("shutdown_any_state", "shutdown also reaches finalized from unconfigured (before any configure) and from "
          "inactive", 2, "__init__ sets self.heartbeat_publisher = None and self.timer = None, and on_shutdown "
          "destroys each only if it is not None: shutdown may come before configure ever ran", needs=("managed",)),
]


class _Lifecycle:
    """The grader's ``ros2 lifecycle`` for one learner node: get_state and change_state calls.

    Args:
        node: the started node (its ``name`` is the node the services belong to).
    """

    def __init__(self, s: GradingSession, node: kit.StartedNode, graph: Any = None) -> None:
        # lifecycle_msgs is a wheel of the venv, not a course package (no s.interface_type); imported
        # here because graders load for CHECKS without ROS
        from lifecycle_msgs.srv import ChangeState, GetState  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

        self.s, self.node, self.graph = s, node, graph
        self.change_state_type, self.get_state_type = ChangeState, GetState
        self.get_state_name = f"/{node.name}/get_state"
        self.change_state_name = f"/{node.name}/change_state"

    def state(self) -> tuple[int, str]:
        """``(state id, what ros2 lifecycle get would say)``; id 0 when there was no answer."""
        response, why = self._ask(self.get_state_type, self.get_state_name, self.get_state_type.Request())
        if response is None:
            return 0, why
        return response.current_state.id, response.current_state.label or STATE_LABELS.get(response.current_state.id, "?")

    def change(self, transition: int) -> tuple[bool | None, str]:
        """Ask for ``transition`` (a Transition id): ``(success, "")``, or ``(None, why)`` without an answer."""
        request = self.change_state_type.Request()
        request.transition.id = transition
        response, why = self._ask(self.change_state_type, self.change_state_name, request)
        return (None, why) if response is None else (bool(response.success), "")

    def _ask(self, srv_type: type, service: str, request: Any) -> tuple[Any, str]:
        """One call from the node's graph (``_services.ask`` when it is the session's own)."""
        if self.graph is None:
            return _services.ask(self.s, srv_type, service, request, self.node, timeout=ANSWER_TIMEOUT)
        if self.node.ended():
            return None, f"not asked, {kit.process_state(self.node.proc)}"
        try:
            return call_service(self.graph, srv_type, service, request, timeout=ANSWER_TIMEOUT), ""
        except TimeoutError as exc:
            return None, f"{exc}; {kit.process_state(self.node.proc)}"


def grade(s: GradingSession) -> None:
    """Start the node, drive it through every transition and watch /heartbeat in each state, then Ctrl+C."""
    # a wheel of the venv; imported here because graders load for CHECKS without ROS
    from std_msgs.msg import String  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    path = kit.executable(s, "executable", PACKAGE, EXECUTABLE)
    probe = ts.listen(s, TOPIC, String)  # before the node starts: nothing it sends is missed
    # a misnamed node is still driven through its own services (need_node=False)
    node = kit.start_node(s, "node_name", path, NODE, sigint_check="sigint_exit", need_node=False)
    if node.name is None:
        raise Unmet(s.results["node_name"].observed)
    life = _Lifecycle(s, node)
    since = _managed(s, life)
    try:
        _quiet(s, "quiet_unconfigured", probe, node, since, "unconfigured")
        since = _transition(s, "configure", life, CONFIGURE, INACTIVE)
        _quiet(s, "quiet_inactive", probe, node, since, "inactive (after configure)")
        since = _transition(s, "activate", life, ACTIVATE, ACTIVE)
        _active(s, probe, node, since)
        since = _transition(s, "deactivate", life, DEACTIVATE, INACTIVE)
        _quiet(s, "quiet_deactivated", probe, node, since, "inactive (after deactivate)")
        _cleanup(s, life)
        _reconfigure(s, life, probe)
        _shutdown(s, life, probe)
    finally:  # judged whatever stopped the sequence above: the runs are of their own
        _shutdown_any_state(s, path, node.name)


#: Seconds for a further run's lifecycle services to show in its graph (only a node that never serves them,
#: already failed by ``managed``, waits that long).
RUN_TIMEOUT = 10.0
#: The other shutdowns the lesson's state machine draws: (the state shut down from, the transitions that reach it).
OTHER_SHUTDOWNS = ((UNCONFIGURED, ()), (INACTIVE, ((CONFIGURE, "configure", INACTIVE),)))


def _shutdown_any_state(s: GradingSession, path: Any, name: str) -> None:
    """Record ``shutdown_any_state``: two more runs of the node, each in a graph of its own, started at once.

    One is shut down straight from unconfigured (its ``on_shutdown`` runs before any ``on_configure``:
    nothing was created yet), the other configured, then shut down from inactive. Each must answer
    ``success: true`` and reach finalized, as ``ros2 lifecycle set <node> shutdown`` would.
    """
    runs = []
    for origin, steps in OTHER_SHUTDOWNS:
        graph = s.new_graph()  # a fresh graph each: the same node name, never seen by the other runs
        proc = s.launch(path, f"{EXECUTABLE}.shutdown_from_{STATE_LABELS[origin]}", [], graph=graph)
        runs.append((origin, steps, graph, StartedNode(proc, name, True)))
    observed, ok, judged = [], True, 0
    for origin, steps, graph, node in runs:
        origin_label = STATE_LABELS[origin]
        life = _Lifecycle(s, node, graph)
        # not ts.wait_for_endpoint: it stops 1 s after the node's first service, and two runs starting at once on
        # a loaded machine show their parameter services seconds before the lifecycle ones (seen in dev validate)
        with s.phase("start"):
            wait_until(lambda: life.change_state_name in ts.endpoints(graph, name, "services"), RUN_TIMEOUT,
                       interval=0.05, abort=node.ended)
        if life.change_state_name not in ts.endpoints(graph, name, "services"):
            ok = False
            observed.append(f"from {origin_label}: a new run served no {life.change_state_name}; "
                            f"{kit.process_state(node.proc)}")
            continue
        said = []
        for transition, label, target in steps:
            success, why = life.change(transition)
            state, state_label = life.state()
            said.append(f"{label} -> {state_label} [{state}]" if success is not None else f"{label}: {why}")
        state, state_label = life.state()
        if state != origin:  # e.g. configure fails: judged by `configure`, not counted twice
            observed.append(f"from {origin_label}: not judged, {origin_label} was not reached "
                            f"({', '.join(said) or f'the node is {state_label}'})")
            continue
        judged += 1
        success, why = life.change(SHUTDOWN_FROM[origin])
        final, final_label = life.state()
        done = bool(success) and final == FINALIZED
        ok = ok and done
        observed.append(f"from {origin_label}" + (f" ({', '.join(said)})" if said else "") + ": " + (
            f"no answer to shutdown: {why}" if success is None else
            f"shutdown {'succeeded' if success else 'failed (success: false)'}, the node is now {final_label} [{final}]"
            + ("" if done else f"; {kit.process_state(node.proc)}")))
    s.record("shutdown_any_state", ok and judged > 0, "; ".join(observed),
             "ros2 lifecycle set <node> shutdown: 'Transition successful' and finalized [4], from unconfigured "
             "(a node just started) and from inactive (after configure)")


def _managed(s: GradingSession, life: _Lifecycle) -> float:
    """Record ``managed``: get_state answers and says unconfigured; returns when that was known (wall clock).

    Raises:
        Unmet: no lifecycle services (nothing to drive), or not unconfigured at start.
    """
    found = ts.wait_for_endpoint(s, life.node.name, "services", life.get_state_name, ANSWER_TIMEOUT,
                                 abort=life.node.ended)
    expected = f"{life.get_state_name} [lifecycle_msgs/srv/GetState] answering 'unconfigured' [1]"
    if life.get_state_name not in found:
        s.record("managed", False, f"{life.node.name} serves no {life.get_state_name} (a plain Node?); its "
                 f"services: {ts.describe_endpoints(found)}; {kit.process_state(life.node.proc)}", expected)
        s.require("managed")
    state, label = life.state()
    s.record("managed", state == UNCONFIGURED, f"{life.get_state_name} says {label} [{state}]", expected)
    s.require("managed")
    return time.time()


def _transition(s: GradingSession, check_id: str, life: _Lifecycle, transition: int, target: int) -> float:
    """Record ``check_id``: ``transition`` succeeds and get_state then says ``target``; returns when (wall clock).

    Raises:
        Unmet: the transition failed (the states the lesson goes on to judge were not reached).
    """
    name = STATE_LABELS[target]
    label = {CONFIGURE: "configure", CLEANUP: "cleanup", ACTIVATE: "activate", DEACTIVATE: "deactivate"}[transition]
    before = time.time()
    success, why = life.change(transition)
    state, state_label = life.state()
    expected = f"ros2 lifecycle set /{life.node.name} {label}: 'Transition successful', then state {name} [{target}]"
    if success is None:
        observed = f"no answer to {label}: {why}"
    else:
        observed = (f"{label} {'succeeded' if success else 'failed (success: false)'}; "
                    f"the node is now {state_label} [{state}]")
    s.record(check_id, bool(success) and state == target, observed, expected)
    s.require(check_id)
    return max(before, time.time())


def _sent_in(probe: Any, since: float, until: float | None = None) -> list[tuple[float, Any]]:
    """``(send stamp, message)`` of the messages written in ``[since, until)`` (wall clock seconds)."""
    stamps = probe.send_stamps()
    messages = probe.messages()
    return [(t, m) for t, m in zip(stamps, messages) if t >= since and (until is None or t < until)]


def _quiet(s: GradingSession, check_id: str, probe: Any, node: kit.StartedNode, since: float, state: str) -> bool:
    """Record ``check_id``: no message sent on /heartbeat for :data:`QUIET` s from ``since`` (wall clock).

    Ends early at the first message sent in the window.
    """
    with s.phase("observe"):
        wait_until(lambda: bool(_sent_in(probe, since)), QUIET, abort=node.ended)
    until = time.time()
    leaked = _sent_in(probe, since, until)
    expected = f"no message on {TOPIC} while {state}, watched for {QUIET:.1f} s"
    if leaked:
        return s.record(check_id, False, f"{len(leaked)} message(s) sent while {state} within "
                        f"{until - since:.1f} s, the first {leaked[0][0] - since:.2f} s in: "
                        f"'{leaked[0][1].data[:60]}'", expected, window=(since, until))
    return s.record(check_id, True, f"nothing sent while {state} in {until - since:.1f} s", expected,
                    window=(since, until))


def _heartbeats(s: GradingSession, probe: Any, node: kit.StartedNode, since: float) -> tuple[list[float], float]:
    """Wait for :data:`SAMPLES` messages sent after ``since``; ``(their send stamps, seconds waited)``."""
    begin = time.monotonic()
    with s.phase("observe"):
        wait_until(lambda: len(_sent_in(probe, since)) >= SAMPLES, SAMPLES * PERIOD + kit.LATE_DELIVERY,
                   abort=node.ended)
    return [t for t, _ in _sent_in(probe, since)][:SAMPLES], time.monotonic() - begin


def _active(s: GradingSession, probe: Any, node: kit.StartedNode, since: float) -> None:
    """Record ``active_messages`` and ``active_rate`` from the messages sent after activate."""
    stamps, waited = _heartbeats(s, probe, node, since)
    expected = f"{TOPIC_TYPE} messages on {TOPIC} once active"
    if not stamps:
        topics = f"topics seen: {ts.learner_topics(s.ros)}"
        s.record("active_messages", False, f"nothing sent on {TOPIC} in {waited:.1f} s of the active state; "
                 f"{topics}; {kit.process_state(node.proc)}", expected)
        return
    texts = [m.data for _, m in _sent_in(probe, since)][:SAMPLES]
    numbers = [int(found.group(1)) if (found := HEARTBEAT.fullmatch(text)) else None for text in texts]
    counting = None not in numbers and all(b - a == 1 for a, b in itertools.pairwise(numbers))
    s.record("active_messages", counting,
             f"{len(stamps)} message(s): " + ", ".join(repr(text[:40]) for text in texts[:4])
             + (" ..." if len(texts) > 4 else "") + ("" if counting else
             ": not 'Heartbeat N' with N one more each time"),
             f"{expected}, 'Heartbeat N' with N counting up by one")
    kit.rate(s, "active_rate", stamps, period=PERIOD, needed=SAMPLES, waited=waited, noun="message",
             source="the messages' send stamps")


def _cleanup(s: GradingSession, life: _Lifecycle) -> None:
    """Record ``cleanup``: the transition succeeds, the node is unconfigured and publishes nothing any more.

    Raises:
        Unmet: cleanup failed (there is nothing to configure again).
    """
    success, why = life.change(CLEANUP)
    state, label = life.state()
    expected = (f"ros2 lifecycle set /{life.node.name} cleanup: 'Transition successful', state unconfigured [1], "
                f"and no publisher of {TOPIC} left on the node (ros2 node info)")
    if not success or state != UNCONFIGURED:
        s.record("cleanup", False, f"no answer to cleanup: {why}" if success is None else
                 f"cleanup {'succeeded' if success else 'failed (success: false)'}; the node is now {label} [{state}]",
                 expected)
        s.require("cleanup")

    def gone() -> bool:
        return TOPIC not in ts.endpoints(s.ros, life.node.name, "publishers")

    with s.phase("observe"):
        wait_until(gone, GONE_TIMEOUT, interval=0.05, abort=life.node.ended)
    left = ts.endpoints(s.ros, life.node.name, "publishers")
    s.record("cleanup", TOPIC not in left, f"cleanup succeeded, the node is {label} [{state}]; " + (
             f"its publishers now: {ts.describe_endpoints(left)}" if TOPIC not in left else
             f"{GONE_TIMEOUT:.0f} s later it still publishes {TOPIC} (publishers: {ts.describe_endpoints(left)})"),
             expected)


def _reconfigure(s: GradingSession, life: _Lifecycle, probe: Any) -> None:
    """Record ``reconfigure``: configure and activate succeed again, and heartbeats come every PERIOD s.

    Not tried after a failed cleanup (the node would be configured over what it still holds); shutdown is
    then judged from unconfigured.
    """
    if s.unmet_need("reconfigure") is not None:
        return
    expected = (f"configure then activate: both 'Transition successful', then one message every {PERIOD} s "
                f"(± {kit.RATE_TOLERANCE:.0%}) on {TOPIC}")
    steps = []
    for transition, label, target in ((CONFIGURE, "configure", INACTIVE), (ACTIVATE, "activate", ACTIVE)):
        since = time.time()
        success, why = life.change(transition)
        state, state_label = life.state()
        if not success or state != target:
            steps.append(f"no answer to {label}: {why}" if success is None else
                         f"{label} {'succeeded' if success else 'failed (success: false)'}; "
                         f"the node is now {state_label} [{state}]")
            s.record("reconfigure", False, "after cleanup: " + "; ".join(steps), expected)
            return
        steps.append(f"{label} succeeded")
    stamps, waited = _heartbeats(s, probe, life.node, since)
    stats = kit.RateStats.from_times(stamps)
    if stats is None or stats.samples < SAMPLES - 1:
        s.record("reconfigure", False, f"after cleanup: {', '.join(steps)}; then only {len(stamps)} message(s) in "
                 f"{waited:.1f} s; {kit.process_state(life.node.proc)}", expected)
        return
    s.record("reconfigure", stats.within(1.0 / PERIOD, kit.RATE_TOLERANCE),
             f"after cleanup: {', '.join(steps)}; then {stats.describe()} (from the messages' send stamps)",
             expected, window=(stamps[0], stamps[-1]))


def _shutdown(s: GradingSession, life: _Lifecycle, probe: Any) -> None:
    """Record ``shutdown``: from the current state (active when all went well) to finalized, then quiet."""
    state, label = life.state()
    transition = SHUTDOWN_FROM.get(state)
    expected = (f"ros2 lifecycle set /{life.node.name} shutdown: 'Transition successful', state finalized [4], "
                f"then no message on {TOPIC} for {QUIET:.1f} s")
    if transition is None:
        s.record("shutdown", False, f"not asked: the node is {label} [{state}], no shutdown transition from there",
                 expected)
        return
    success, why = life.change(transition)
    since = time.time()
    final, final_label = life.state()
    if not success or final != FINALIZED:
        s.record("shutdown", False, f"no answer to shutdown from {label}: {why}" if success is None else
                 f"shutdown from {label} {'succeeded' if success else 'failed (success: false)'}; "
                 f"the node is now {final_label} [{final}]", expected)
        return
    with s.phase("observe"):
        wait_until(lambda: bool(_sent_in(probe, since)), QUIET, abort=life.node.ended)
    until = time.time()
    leaked = _sent_in(probe, since, until)
    s.record("shutdown", not leaked, f"shutdown from {label} succeeded, the node is {final_label}; " + (
        f"{len(leaked)} message(s) sent after it within {until - since:.1f} s (a timer still running?)" if leaked
        else f"nothing sent in the {until - since:.1f} s after it"), expected, window=(since, until))
