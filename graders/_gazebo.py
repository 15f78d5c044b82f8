"""The steps of the ``gazebo-custom-nodes`` grader (graders/gazebo_custom_nodes.py): one function per run of the
learner's three nodes, and the lesson's contract values they and the grader's ``CHECKS`` share
(chapters/gazebo-custom-nodes/CONTRACT.md). A helper of one lesson (the placement rule in ``ros2course.kit``'s
docstring).

Gazebo never runs here: the grader's world (:mod:`ros2course.kit.world`, MuJoCo) serves the author's
``shapes_with_tf2_and_wrench`` box, its ``set_pose`` service, its wrench topic, the box on ``/tf`` and
``/clock``, as Gazebo and ``ros_gz_bridge`` would.

* ``send_poses_to_gazebo_node``: the world (and so the service) appears only after the node said it waits;
  then its one request is judged (the box, where, upright) and the node must end by itself.
* ``send_wrenches_to_gazebo_node``: nothing subscribes to the wrench topic until the node said it waits; then
  its one message is judged (entity, force, torque), and the node must keep spinning.
* ``control_shape_thrust_node``, on the world's clock (``use_sim_time:=true``), in lockstep: after each 0.004 s
  step the world waits for the controller's answer, so a loaded machine slows the run but never changes the
  physics judged. From the box at rest at x = 0: every step's force against the lesson's law (from the pose
  published before it), an answer to every step, and where the box comes to rest against where the law
  brings it in the same world (:func:`ideal_run`).

Positions are metres in the world frame, forces newtons, times seconds (sim seconds where said).
ROS modules are imported inside the functions that grade: a grader module is also loaded for its CHECKS
alone (``ros2course list``, ``hint``), where ROS is not needed.
"""

from __future__ import annotations

import ast
import math
import re
import time
from collections.abc import Callable
from typing import Any

import yaml

from ros2course import kit
from ros2course.kit import Session, Unmet, services
from ros2course.kit import launch as launching
from ros2course.kit import world as sim

PACKAGE = "python_package_that_uses_gazebo"
POSE_EXECUTABLE = POSE_NODE = "send_poses_to_gazebo_node"
WRENCH_EXECUTABLE = WRENCH_NODE = "send_wrenches_to_gazebo_node"
THRUST_EXECUTABLE = THRUST_NODE = "control_shape_thrust_node"
WORLD = sim.WORLD
SET_POSE = f"/world/{WORLD}/set_pose"
WRENCH_TOPIC = f"/world/{WORLD}/wrench"
#: The pose the pose client asks for (metres, world frame), upright (x, y, z, w).
POSE_POSITION = (0.0, 0.0, 50.0)
IDENTITY = (0.0, 0.0, 0.0, 1.0)
#: The push (newtons, world frame) the wrench publisher sends once, and the entity id it sends it to (the box's
#: link in Gazebo; gz-sim finds a wrench's entity by id, not by name).
PUSH = (1000.0, 0.0, 0.0)
ENTITY_ID = sim.BOX_LINK_ID
#: The thrust controller's law: a force on x of -GAIN * (x - TARGET_X) newtons.
TARGET_X = -3.0
GAIN = 5.0
VALUE_TOLERANCE = 1e-6  # the values are given exactly
#: Newtons: a step's force may differ this much (plus 0.1 %) from the law at the pose published before it.
FORCE_TOLERANCE = 0.01
#: Steps of the closed-loop run (4 s of sim time: the box is at rest after about 1.6 s).
STEPS = 1000
#: Metres and m/s: where the box comes to rest, against where the law brings it in the same world.
REST_TOLERANCE = 0.02
REST_SPEED = 0.01
#: Fraction of the steps that must get an answer (a force from the controller), and that must follow the law.
ANSWERED = 0.95
#: Wall seconds the world waits for the controller's answer to a step once the run is judged (lockstep; a
#: correct controller answers in about 2 ms, 50 ms on a loaded machine), and before (while the controller
#: starts: the box rests).
LOCKSTEP_WAIT = 0.5
STARTUP_WAIT = 0.5
#: Wall seconds the judged run may take (a correct controller: about 2 s; one that answers every third step
#: makes the world wait LOCKSTEP_WAIT for each of the others, and is judged on the steps run by then).
RUN_LIMIT = 30.0
#: Seconds: for a node's first "waiting" record; what it waits for then stays missing THROTTLE_WINDOW more.
WAIT_WINDOW = 3.0
THROTTLE_WINDOW = 2.5
#: Wall seconds, after the first "waiting" record is seen, for the second of a node that goes on waiting (the
#: wrench publisher, the thrust controller): a bound on seeing it, never on the node (its stamps are judged
#: against LOOK_AGAIN). 2.5 s missed the wrench publisher's in 1 reference run of 20 at load 2, beside another
#: grading's lockstep thrust run; a correct node's comes about 1 s after its first, so the longer bound costs
#: nothing but for a node that stopped waiting.
SECOND_RECORD_WINDOW = 4.0
#: Seconds the wrench publisher and the thrust controller are watched after they said twice that they wait,
#: before the world appears (their records over that span judged: at most one a second).
STILL_WAITING_WINDOW = 1.0
#: Seconds: the longest gap between two records of a node that says so "once a second" (its records' own
#: stamps): a spin_once(timeout_sec=1.0) loop or a throttle_duration_sec=1.0 warning, late on a loaded
#: machine, against a loop or throttle of 2 s (held-out seed 36: both passed while only "at most once a
#: second" was judged).
LOOK_AGAIN = 1.5
#: Wall seconds the world's clock runs with no /tf once the controller subscribes to /tf (thrust_no_transform):
#: a warning throttled to one a second comes three or four times (two at least, LOOK_AGAIN apart at most), an
#: unthrottled one about 250 times a second
NO_TF_WINDOW = 3.5
#: rcl_interfaces/msg/Log's level of a warning (WARN); ERROR and FATAL are above it
WARN_LEVEL = 30
#: Seconds: for the request or message once the world is there; for a node to end by itself; for the
#: controller's first answer (a node that starts, then waits for the world's subscriber and /clock).
SEND_TIMEOUT = 3.0
END_TIMEOUT = 3.0
ANSWER_TIMEOUT = 15.0
#: A log record of the wrench node that gives the force it sent: 1000 (N) as a number ("1000", "1000.0", "1e3"
#: and "1.0e+03" too), not part of a longer one.
SENT_FORCE = re.compile(r"(?<![\d.])(1000(\.0*)?|1(\.0*)?e\+?0*3)(?![\d])", re.IGNORECASE)
#: Wall seconds the world takes to answer the pose client (gz-sim answers a bridged request after its next
#: update): a client that does not wait for its answer has ended by then (rclpy's shutdown takes ~0.1 s).
ANSWER_DELAY = 1.5
#: The bridge file the thrust launch file configures ros_gz_bridge with, and what it must bridge:
#: (ros_topic_name, gz_topic_name, ros_type_name, gz_type_name, direction).
BRIDGE_FILE = "control_shape_thrust.yaml"
BRIDGE = (
    ("/clock", "/clock", "rosgraph_msgs/msg/Clock", "gz.msgs.Clock", "GZ_TO_ROS"),
    ("/tf", "/model/box/pose", "tf2_msgs/msg/TFMessage", "gz.msgs.Pose_V", "GZ_TO_ROS"),
    (WRENCH_TOPIC, WRENCH_TOPIC, "ros_gz_interfaces/msg/EntityWrench", "gz.msgs.EntityWrench", "ROS_TO_GZ"),
)
BRIDGE_KEYS = ("ros_topic_name", "gz_topic_name", "ros_type_name", "gz_type_name", "direction")
#: The launch files: (file, executable, what its parameter_bridge must carry: an argument or a config file).
LAUNCH_FILES = (
    ("send_poses_to_gazebo_launch.py", POSE_EXECUTABLE, f"{SET_POSE}@ros_gz_interfaces/srv/SetEntityPose"),
    ("send_wrenches_to_gazebo_launch.py", WRENCH_EXECUTABLE,
     f"{WRENCH_TOPIC}@ros_gz_interfaces/msg/EntityWrench]gz.msgs.EntityWrench"),
    ("control_shape_thrust_launch.py", THRUST_EXECUTABLE, BRIDGE_FILE),
)


def law(x: float) -> float:
    """The lesson's force (N) on x for the box at ``x`` metres."""
    return -GAIN * (x - TARGET_X)


def _shown(values: tuple[float, ...]) -> str:
    return "(" + ", ".join(f"{v:g}" for v in values) + ")"


def _close(found: tuple[float, ...], wanted: tuple[float, ...], tolerance: float = VALUE_TOLERANCE) -> bool:
    return all(abs(a - b) <= tolerance for a, b in zip(found, wanted, strict=True))


def _records(rosout: Any, node: str) -> list[str]:
    return [" ".join(r.msg.split()) for r in rosout.records(node=node)]


def _last(rosout: Any, node: str, count: int = 3) -> str:
    return " | ".join(text[:80] for text in _records(rosout, node)[-count:]) or "no log records"


def _gone(proc: kit.LearnerProcess) -> Callable[[], bool]:
    def gone() -> bool:
        return proc.poll() is not None and time.monotonic() - (proc.ended_at or 0.0) > kit.LATE_DELIVERY

    return gone


def says_it_waits(s: Session, check_id: str, rosout: Any, node: kit.StartedNode, node_name: str, what: str,
                  keeps: float = 0.0) -> bool:
    """Record ``check_id``: within :data:`WAIT_WINDOW` s, with ``what`` missing, the node logs that it waits (a
    record holding "wait" or "availab"); with ``keeps`` (seconds), it says so again within that long after
    the first record (a loop that gives up after one look says it once), its second record stamped at most
    :data:`LOOK_AGAIN` s after its first (it looks once a second, not every two)."""
    def said() -> list:
        return rosout.records(node=node_name, match=lambda text: services.WAITING.search(text) is not None)

    with s.phase("observe"):
        kit.wait_until(lambda: bool(said()), WAIT_WINDOW, abort=node.ended)
        if keeps and said():
            kit.wait_until(lambda: len(said()) > 1, keeps, abort=node.ended)
    found = said()
    expected = f"a log record saying it waits while {what} is missing (e.g. '... not available, waiting...')" + (
        f", again within {keeps:g} s while it is still missing (it goes on waiting: once a second, the second "
        f"record at most {LOOK_AGAIN:g} s after the first)" if keeps else "")
    if found and keeps and len(found) < 2:
        return s.record(check_id, False, f"logged '{found[0].msg.strip()[:120]}' once, and not again in the "
                        f"{keeps:g} s after with {what} still missing: it stopped waiting", expected)
    if found and keeps:
        first, second = sorted(kit.stamp_seconds(r.stamp) for r in found)[:2]
        if second - first > LOOK_AGAIN:
            return s.record(check_id, False, f"logged '{found[0].msg.strip()[:120]}', then again only "
                            f"{second - first:.1f} s later: it looks less often than once a second", expected,
                            "rclpy.spin_once(self, timeout_sec=1.0) between two looks")
    if found:
        return s.record(check_id, True, f"logged '{found[0].msg.strip()[:120]}' while {what} was missing"
                        + (f", {len(found)} times" if keeps else ""), expected)
    return s.record(check_id, False, f"in {WAIT_WINDOW:.0f} s with {what} missing: {_last(rosout, node_name)}; "
                    f"{kit.process_state(node.proc)}", expected)


def ends(s: Session, check_id: str, proc: kit.LearnerProcess, when: str, *, after: Any = None,
         expected: str = "") -> bool:
    """Record ``check_id``: ``proc`` ends by itself within :data:`END_TIMEOUT` s, exit code 0, no traceback
    (and, with ``after``, a callable giving the ``time.monotonic()`` of what it must wait for or None, not
    before that)."""
    waited = END_TIMEOUT + (ANSWER_DELAY if after else 0.0)  # the world answers ANSWER_DELAY s after a request
    with s.phase("observe"):
        kit.wait_until(lambda: proc.poll() is not None, waited)
    expected = expected or f"the process ends by itself within {END_TIMEOUT:.0f} s, exit code 0, no traceback"
    ended = proc.exit_state()
    if ended is None:
        return s.record(check_id, False, f"still running {waited:g} s {when}", expected)
    waited_for = after() if after else None
    ended_at = proc.ended_at or time.monotonic()  # None: reaped by poll() just now
    if after and (waited_for is None or ended_at < waited_for):
        early = "" if waited_for is None else f" {waited_for - ended_at:.1f} s"
        return s.record(check_id, False, f"the process {ended.describe()}{early} before the world answered its "
                        "request: it did not wait for the answer", expected)
    traceback = "Traceback (most recent call last)" in proc.stderr() + proc.stdout()
    ok = ended.returncode == 0 and not traceback
    return s.record(check_id, ok, f"{when}, the process {ended.describe()}"
                    + (f" ({ended.last_line})" if ended.last_line and not ok else ""), expected)


def interrupted_run(s: Session, check_id: str, path: Any, node: str, label: str) -> None:
    """``check_id`` (a Ctrl+C check): start ``path`` with no world at all; once it has logged (that it waits),
    Ctrl+C is pressed as the part ends (:func:`kit.ctrl_c_once_it_logs`)."""
    kit.ctrl_c_once_it_logs(s, check_id, lambda suffix: s.launch(path, label + suffix, []), node,
                            patience=2 * WAIT_WINDOW)


# --- the pose client ---------------------------------------------------------------------------------------

def pose_run(s: Session, path: Any) -> None:
    """pose_node_name, pose_waits, pose_waits_throttled, pose_request, pose_ends: the world appears only
    :data:`THROTTLE_WINDOW` s after the node said it waits."""
    rosout = s.graph.rosout()
    node = kit.start_node(s, "pose_node_name", path, POSE_NODE)
    if says_it_waits(s, "pose_waits", rosout, node, node.name or POSE_NODE, f"the service {SET_POSE}"):
        services.waits_throttled(s, "pose_waits_throttled", rosout, node, node_name=node.name or POSE_NODE,
                                 window=THROTTLE_WINDOW)
    world = sim.physics_world(s, answer_delay=ANSWER_DELAY)
    with s.phase("observe"):
        kit.wait_until(lambda: bool(world.set_pose_requests), SEND_TIMEOUT + END_TIMEOUT, abort=_gone(node.proc))
    expected = (f"one SetEntityPose request for the box (entity.name 'box'), position {_shown(POSE_POSITION)}, "
                f"orientation {_shown(IDENTITY)} (upright)")
    if not world.set_pose_requests:
        s.record("pose_request", False, f"no request to {SET_POSE} in {SEND_TIMEOUT + END_TIMEOUT:.0f} s once it "
                 f"was there; last log records: {_last(rosout, node.name or POSE_NODE)}; {kit.process_state(node.proc)}", expected)
        s.require("pose_request")
    ends(s, "pose_ends", node.proc, "once the world had answered its request",
         after=lambda: world.set_pose_requests[0].answered_at,
         expected=f"the node waits for the world's answer ({ANSWER_DELAY:.1f} s after its request here), then ends "
                  f"by itself within {END_TIMEOUT:.0f} s: exit code 0, no traceback")
    requests = list(world.set_pose_requests)
    first = requests[0]
    box = world.box_state()
    problems = []
    if first.target != sim.BOX_ID:  # the box model: its name, or its id
        problems.append(f"entity (id {first.entity[0]}, name '{first.entity[1]}') is not the box")
    if not _close(first.position, POSE_POSITION):
        problems.append(f"position {_shown(first.position)}")
    if not _close(first.orientation, IDENTITY):
        problems.append(f"orientation {_shown(first.orientation)}")
    if len(requests) > 1:
        problems.append(f"{len(requests)} requests")
    s.record("pose_request", not problems,
             "; ".join(problems) + f" (the box is now at {_shown(tuple(round(v, 2) for v in box.position))})"
             if problems else f"one request: the box at {_shown(first.position)}, upright; the world's box was then "
             f"at z = {box.position[2]:.1f} m, falling", expected)


# --- the wrench publisher ------------------------------------------------------------------------------------

def wrench_run(s: Session, path: Any) -> None:
    """wrench_node_name, wrench_waits, wrench_waits_throttled, wrench_sent, wrench_once, wrench_logged,
    wrench_values, wrench_spins (and wrench_sigint_exit when the part ends): nothing subscribes to the wrench topic until
    :data:`STILL_WAITING_WINDOW` s after it said a second time that it waits (the lesson's "once a second":
    at most, and at least, judged as the thrust controller's; gazebo held-out seed 37: spin_once(timeout_sec=2.0)
    passed while only "at most" was)."""
    rosout = s.graph.rosout()
    node = kit.start_node(s, "wrench_node_name", path, WRENCH_NODE, sigint_check="wrench_sigint_exit")
    if says_it_waits(s, "wrench_waits", rosout, node, node.name or WRENCH_NODE, f"a subscriber on {WRENCH_TOPIC}",
                     keeps=SECOND_RECORD_WINDOW):
        services.waits_throttled(s, "wrench_waits_throttled", rosout, node, node_name=node.name or WRENCH_NODE,
                                 window=STILL_WAITING_WINDOW)
    world = sim.physics_world(s)
    with s.phase("observe"):
        kit.wait_until(lambda: bool(world.wrenches), SEND_TIMEOUT, abort=_gone(node.proc))
    if not world.wrenches:
        s.record("wrench_sent", False, f"no message on {WRENCH_TOPIC} in {SEND_TIMEOUT:.0f} s once the world "
                 "subscribed (one published before a subscriber matched is lost); last log records: "
                 f"{_last(rosout, node.name or WRENCH_NODE)}; {kit.process_state(node.proc)}",
                 f"one EntityWrench on {WRENCH_TOPIC} once the world subscribes")
        s.require("wrench_sent")
    s.record("wrench_sent", True, f"an EntityWrench on {WRENCH_TOPIC} once the world subscribed",
             f"one EntityWrench on {WRENCH_TOPIC} once the world subscribes")
    with s.phase("observe"):  # more messages, and the push's effect (the box slides about 0.8 m in 0.4 s)
        kit.wait_until(lambda: False, 2.0, abort=_gone(node.proc))
    count = len(world.wrenches)
    s.record("wrench_once", count == 1, f"{count} message(s) in the 2 s after the first", "one message")
    first = world.wrenches[0]
    problems = []
    if first.link != ENTITY_ID:
        problems.append(f"entity id {first.entity[0]}, name '{first.entity[1]}', type {first.entity[2]}: "
                        f"{'no entity Gazebo finds' if first.link is None else f'entity {first.link}'}")
    if not _close(first.force, PUSH):
        problems.append(f"force {_shown(first.force)} N")
    if not _close(first.torque, (0.0, 0.0, 0.0)):
        problems.append(f"torque {_shown(first.torque)} N m")
    logged = rosout.records(node=node.name or WRENCH_NODE,
                            match=lambda text: services.WAITING.search(text) is None and SENT_FORCE.search(text))
    s.record("wrench_logged", bool(logged), f"logged '{logged[0].msg.strip()[:120]}'" if logged else
             f"no record with the force (1000) among its records: {_last(rosout, node.name or WRENCH_NODE)}",
             "a log record, after the wait, of what it sent: the force, 1000 N (any wording)")
    x = world.box_state().position[0]
    s.record("wrench_values", not problems, ("; ".join(problems) if problems else
             f"entity {first.entity[0]}, force {_shown(first.force)} N, no torque")
             + f"; the box slid to x = {x:.2f} m", f"entity.id {ENTITY_ID} (the box's link), force "
             f"{_shown(PUSH)} N, torque 0 (the box slides about 0.81 m along x)")
    running = node.proc.poll() is None
    s.record("wrench_spins", running, "still running 2 s after sending" if running else
             f"{kit.process_state(node.proc)} after sending", "the node keeps spinning (rclpy.spin) until Ctrl+C")


# --- the thrust controller ------------------------------------------------------------------------------------

def ideal_run(steps: int = STEPS) -> list[sim.StepRecord]:
    """The steps the lesson's law makes from the SDF's start, at rest, in ``steps`` steps of the grader's world:
    each step's force computed from the pose published after the step before (the first step, as in the
    judged run, takes none)."""
    world = sim.BoxWorld()
    force = (0.0, 0.0, 0.0)
    for _ in range(steps):
        entry = world.step(force)
        force = (law(entry.position[0]), 0.0, 0.0)
    return world.trajectory


def _plot(s: Session, steps: list[sim.StepRecord], ideal: list[sim.StepRecord], points: int = 60) -> None:
    """Hand ``check`` the box's x against sim time beside the law's (``ros2course evidence``); never costs a grade."""
    count = min(len(steps), len(ideal))
    if count < 2:
        return
    index = list(range(0, count, max(1, count // points)))
    start = steps[0].time - sim.STEP_SIZE
    s.add_plot("the box's x on the world's clock (s), yours and the law's", [steps[i].time - start for i in index],
               {"x": [steps[i].position[0] for i in index], "law": [ideal[i].position[0] for i in index]}, "m")


def thrust_run(s: Session, path: Any) -> None:
    """thrust_node_name, thrust_waits, thrust_waits_throttled, thrust_entity, thrust_rate, thrust_law, thrust_settles (and
    thrust_sigint_exit when the part ends): with no world, the controller must say it waits for a subscriber
    (within :data:`WAIT_WINDOW` s); then the world appears with its clock alone (:func:`no_transform_yet`), then
    runs the controller on the world's clock, in lockstep, from the box at rest at x = 0."""
    rosout = s.graph.rosout()
    node = kit.start_node(s, "thrust_node_name", path, THRUST_NODE, sigint_check="thrust_sigint_exit",
                          args=["--ros-args", "-p", "use_sim_time:=true"])
    if says_it_waits(s, "thrust_waits", rosout, node, node.name or THRUST_NODE, f"a subscriber on {WRENCH_TOPIC}",
                     keeps=SECOND_RECORD_WINDOW):
        # the lesson's "waits as node 2 does" includes node 2's once a second (held-out seed 28: a wait loop
        # without its spin_once logged as fast as it could, and passed)
        services.waits_throttled(s, "thrust_waits_throttled", rosout, node, node_name=node.name or THRUST_NODE,
                                 window=STILL_WAITING_WINDOW)
    # the world's clock first runs alone, in real time, with no /tf: the lesson's "while the transform is not
    # there yet" (its branch ran only by chance while /tf came with the first tick: cosmic-ray held-out seed 35)
    world = sim.physics_world(s, real_time_factor=1.0, withhold_tf=True)
    no_transform_yet(s, "thrust_no_transform", rosout, node, world)
    world.real_time_factor, world.wait_for_input, world.withhold_tf = None, STARTUP_WAIT, False
    with s.phase("observe"):
        kit.wait_until(lambda: bool(world.wrenches), ANSWER_TIMEOUT, abort=node.ended)
    if not world.wrenches:
        why = (f"no message on {WRENCH_TOPIC} in {ANSWER_TIMEOUT:.0f} s (the world published the box on /tf and "
               f"the time on /clock every step); {kit.process_state(node.proc)}")
        for check_id in ("thrust_entity", "thrust_rate", "thrust_law", "thrust_settles"):
            s.record(check_id, False, why, "a force on the wrench topic at every step of the world")
        raise Unmet(why)
    world.pause()
    world.wait_for_input = LOCKSTEP_WAIT
    start = world.set_box_state()
    heard = len(world.wrenches)
    world.resume()
    end = (start + STEPS) * sim.STEP_SIZE - sim.STEP_SIZE / 2
    with s.phase("observe"):
        done = kit.wait_until(lambda: world.sim_time >= end, RUN_LIMIT, abort=node.ended)
    world.pause()
    steps = [e for e in world.trajectory if e.step >= start][:STEPS]
    _judge_thrust(s, world, steps, world.wrenches[heard:], done)


def no_transform_yet(s: Session, check_id: str, rosout: Any, node: kit.StartedNode, world: sim.PhysicsWorld) -> bool:
    """Record ``check_id``: the world's clock runs with no /tf; from when the controller subscribes to /tf (its
    TransformListener, made after its wait) for :data:`NO_TF_WINDOW` s, it keeps running, publishes no wrench
    and warns (a record at WARN or above) once a second: at most once a second, and again within
    :data:`LOOK_AGAIN` s: the lesson's "while the transform is not there yet, it logs a warning
    (throttle_duration_sec=1.0) and publishes nothing". A record that mentions a subscriber is its wait's, not
    this warning. Stamps are the records' own (wall clock)."""
    name = node.name or THRUST_NODE
    expected = (f"with /clock running and no /tf ({NO_TF_WINDOW:g} s): still running, no message on {WRENCH_TOPIC}, "
                f"a warning once a second (at most one a second, at least two, at most {LOOK_AGAIN:g} s apart)")
    with s.phase("observe"):
        listening = kit.wait_until(lambda: world.peers()[0] > 0, ANSWER_TIMEOUT, abort=node.ended)
        since = time.time()
        if listening:
            kit.wait_until(lambda: False, NO_TF_WINDOW, abort=node.ended)
    sent, running = len(world.wrenches), node.proc.poll() is None
    if not listening:
        return s.record(check_id, False, f"nothing subscribed to /tf in {ANSWER_TIMEOUT:.0f} s after the world "
                        f"appeared; {kit.process_state(node.proc)}", expected,
                        "make the tf2_ros.TransformListener(self.buffer, self) once the wait is over")
    warnings = rosout.records(node=name, match=lambda text: "subscri" not in text.lower())
    stamps = sorted(t for t in (kit.stamp_seconds(r.stamp) for r in warnings if r.level >= WARN_LEVEL) if t >= since)
    span = stamps[-1] - stamps[0] if stamps else 0.0
    allowed = int(span) + 2  # once a second, a timer that catches up after a late tick forgiven (services)
    widest = max((b - a for a, b in zip(stamps, stamps[1:])), default=0.0)
    said = (f"{len(stamps)} warning(s) in {NO_TF_WINDOW:g} s with the clock running and no /tf"
            + (f" ({span:.1f} s from the first to the last, {widest:.1f} s apart at the widest)"
               if len(stamps) > 1 else "")
            + f", {sent} message(s) on {WRENCH_TOPIC}")
    if not running:
        return s.record(check_id, False, f"{said}; {kit.process_state(node.proc)}", expected,
                        "catch tf2_ros.TransformException around lookup_transform: warn and return (an exception "
                        "out of a timer callback ends the node)")
    if sent:
        return s.record(check_id, False, said, expected, "publish nothing without a transform: return after the warning")
    if not stamps:
        return s.record(check_id, False, said, expected, "log the missing transform: self.get_logger().warn(..., "
                        "throttle_duration_sec=1.0)")
    if len(stamps) > allowed:
        return s.record(check_id, False, said, expected + f" (at most {allowed})", "throttle_duration_sec=1.0 on "
                        "the warning: the timer ticks 250 times a second on the world's clock")
    rare = len(stamps) < 2 or widest > LOOK_AGAIN
    return s.record(check_id, not rare, said + (": less often than once a second" if rare else ""), expected,
                    "warn on every tick that finds no transform, throttled to once a second "
                    "(throttle_duration_sec=1.0): not once only, nor every two seconds")


def _judge_thrust(s: Session, world: sim.PhysicsWorld, steps: list[sim.StepRecord], wrenches: list, done: bool) -> None:
    """thrust_entity, thrust_rate, thrust_law, thrust_settles on the judged steps."""
    # _close (|a - b| <= tolerance) rather than |a - b| > tolerance: a NaN is close to nothing, so it is off
    off = [w for w in wrenches if w.link != ENTITY_ID or not _close(w.force[1:], (0.0, 0.0))
           or not _close(w.torque, (0.0, 0.0, 0.0))]
    s.record("thrust_entity", bool(wrenches) and not off,
             f"{len(off)} of {len(wrenches)} messages off, e.g. entity {off[0].entity}, force {_shown(off[0].force)}, "
             f"torque {_shown(off[0].torque)}" if off else f"{len(wrenches)} messages, each for entity "
             f"{ENTITY_ID} with a force along x only", f"entity.id {ENTITY_ID}, force (u, 0, 0), no torque")
    judged = steps[1:]  # the first step after the box was set takes no answer (the world drops stale ones)
    answered = [e for e in judged if e.inputs >= 1 and not e.timed_out]
    share = len(answered) / len(judged) if judged else 0.0
    late = sum(e.timed_out for e in judged)
    s.record("thrust_rate", done and share >= ANSWERED,
             f"{len(answered)} of {len(judged)} steps got a force ({late} waited {LOCKSTEP_WAIT:g} s in vain)"
             + ("" if done else f"; {len(steps)} of the {STEPS} steps ran in {RUN_LIMIT:.0f} s"),
             f"a force for every 0.004 s step of the world (at least {ANSWERED:.0%}): a timer of 0.001 s on "
             "the world's clock ticks once per step")
    # the forces sent (whatever entity they name: thrust_entity judges that), summed per step as Gazebo sums them
    sent: dict[int, float] = {}
    for wrench in wrenches:
        if wrench.step is not None:
            sent[wrench.step] = sent.get(wrench.step, 0.0) + wrench.force[0]
    pairs = [(before.position[0], sent[step.step]) for before, step in zip(steps, steps[1:]) if step.step in sent]
    wrong = [(x, f) for x, f in pairs if not abs(f - law(x)) <= FORCE_TOLERANCE + 0.001 * abs(law(x))]  # NaN: wrong
    sample = (f"; e.g. {wrong[0][1]:.3f} N at x = {wrong[0][0]:.3f} m (the law: {law(wrong[0][0]):.3f} N)"
              if wrong else "")
    s.record("thrust_law", bool(pairs) and len(wrong) <= (1 - ANSWERED) * len(pairs),
             f"{len(pairs) - len(wrong)} of {len(pairs)} forces follow the law" + sample,
             f"each force -{GAIN:g} * (x - ({TARGET_X:g})) N for the x of the box's latest transform, "
             f"± {FORCE_TOLERANCE} N")
    run = ideal_run(len(steps))
    ideal = run[-1] if run else sim.BoxWorld().state()
    _plot(s, steps, run)
    last = steps[-1] if steps else None
    if last is None:
        s.record("thrust_settles", False, "no step of the world was run", "the box at rest where the law brings it")
        return
    x, speed = last.position[0], math.hypot(*last.linear_velocity)
    moved = [e.position[0] for e in steps]
    ok = done and abs(x - ideal.position[0]) <= REST_TOLERANCE and speed <= REST_SPEED
    s.record("thrust_settles", ok,
             f"after {len(steps) * sim.STEP_SIZE:.1f} s of sim time the box is at x = {x:.3f} m, moving at "
             f"{speed:.3f} m/s (it went from {moved[0]:.2f} to as far as {min(moved):.2f} m)",
             f"at rest at x = {ideal.position[0]:.3f} ± {REST_TOLERANCE} m, where the law brings the box in this world "
             f"(friction holds it once |{GAIN:g} (x + 3)| N is below mu m g = {sim.FRICTION * sim.GRAVITY:.1f} N)")


# --- the files ---------------------------------------------------------------------------------------------

#: Calls whose arguments are parts of one path, joined with '/' (os.path.join, pathlib.Path, launch's substitution).
_PATH_JOINS = {"join", "Path", "PurePath", "PathJoinSubstitution"}
#: Calls that give a package's installed share folder (ament_index_python, launch_ros's substitution).
_SHARE_OF = {"get_package_share_directory", "get_package_share_path", "FindPackageShare"}


def _path_text(node: ast.AST, names: dict[str, ast.AST], depth: int = 0) -> str:
    """The path an expression of a launch file spells, read from its syntax tree (never run): string literals as
    they are, parts of ``os.path.join``/``Path``/``PathJoinSubstitution`` and of ``/`` joined with '/', ``+`` and
    f-strings concatenated, a name its (last) assignment's value; anything else (``get_package_share_directory``,
    ``FindPackageShare``, an unknown value) is ``<?>``."""
    if depth > 8:
        return "<?>"
    def text(n: ast.AST) -> str:
        return _path_text(n, names, depth + 1)
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.Name) and node.id in names:
        return text(names[node.id])
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div):
        return f"{text(node.left)}/{text(node.right)}"
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add):
        return text(node.left) + text(node.right)
    if isinstance(node, ast.JoinedStr):
        return "".join(text(v.value) if isinstance(v, ast.FormattedValue) else text(v) for v in node.values)
    if isinstance(node, ast.Call):
        func = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
        if func in _PATH_JOINS:
            parts = [p for a in node.args for p in (a.elts if isinstance(a, ast.List) else [a])]
            return "/".join(text(p) for p in parts)
        if func in _SHARE_OF and node.args:
            package = _literal(node.args[0], names)
            return "<?>" if package is _UNKNOWN else f"<share:{package}>"
    return "<?>"


#: What :func:`_literal` gives for an expression whose value the syntax tree does not show.
_UNKNOWN = object()


def _literal(node: ast.AST, names: dict[str, ast.AST], depth: int = 0) -> object:
    """The value of a constant expression of a launch file (a literal, or a name whose last assignment is one),
    read from the syntax tree; :data:`_UNKNOWN` for anything else (a call, an argument, a substitution)."""
    if depth > 8:
        return _UNKNOWN
    if isinstance(node, ast.Constant):
        return node.value
    if isinstance(node, ast.Name) and node.id in names:
        return _literal(names[node.id], names, depth + 1)
    return _UNKNOWN


def _assignments(tree: ast.Module) -> dict[str, ast.AST]:
    """Each name of the launch file and the value of its last plain assignment (``PACKAGE = '...'``)."""
    return {target.id: node.value for node in ast.walk(tree) if isinstance(node, ast.Assign)
            for target in node.targets if isinstance(target, ast.Name)}


def _node_package(tree: ast.Module, line: int) -> object:
    """The ``package=`` value of the ``Node(...)`` call at ``line`` (the static reader's
    :attr:`~ros2course.kit.launch.NodeAction.line`), a name resolved to its constant (:func:`_literal`):
    the static reader reads only literals, so ``package=PACKAGE`` is None there whatever PACKAGE holds."""
    names = _assignments(tree)
    for call in ast.walk(tree):
        if isinstance(call, ast.Call) and call.lineno == line:
            for keyword in call.keywords:
                if keyword.arg == "package":
                    return _literal(keyword.value, names)
    return _UNKNOWN


def _parse(text: str) -> ast.Module | None:
    """A launch file's syntax tree (read, never run: the file is the learner's); None when it does not parse."""
    try:
        return ast.parse(text)
    except SyntaxError:
        return None


def _sets_config_file(tree: ast.Module) -> bool:
    """Whether a launch file's syntax tree has a parameter dictionary with the key ``'config_file'`` (a ``{...}``
    whose key is that string), the parameter ros_gz_bridge's parameter_bridge reads its bridge file from. Read from
    the tree, not searched in the text: ``'XXconfig_fileXX'`` holds the words but sets no parameter the bridge
    reads (mutmut held-out seed 42 passed it)."""
    return any(isinstance(key, ast.Constant) and key.value == "config_file"
               for node in ast.walk(tree) if isinstance(node, ast.Dict) for key in node.keys)


def _names_installed_bridge_file(tree: ast.Module) -> bool:
    """Whether a launch file's syntax tree spells a path ending in the installed ``config_bridge/<BRIDGE_FILE>``
    (:func:`_path_text` of every expression: ``os.path.join(share, 'config_bridge', BRIDGE_FILE)``,
    ``PathJoinSubstitution([FindPackageShare(...), 'config_bridge', ...])``, ``Path(share) / 'config_bridge' /
    ...``, an f-string, or a name assigned any of them), the share folder, where the tree shows whose, this
    package's."""
    names = _assignments(tree)
    whole = f"config_bridge/{BRIDGE_FILE}"
    paths = [re.sub(r"/+", "/", _path_text(node, names)) for node in ast.walk(tree) if isinstance(node, ast.expr)]
    # the share folder, where it is named, must be this package's: get_package_share_directory(None) or another
    # package's name raises (PackageNotFoundError) as the launch file runs (mutmut held-out seed 44 passed both)
    return any(path.endswith(whole) and all(p == PACKAGE for p in re.findall(r"<share:([^>]*)>", path))
               for path in paths)


def _bridges(argument: object, carried: str) -> bool:
    """Whether one parameter_bridge argument is the bridge ``carried`` spells: ``topic@ros_type]gz_type`` (ROS to
    Gazebo) or ``service@ros_srv_type`` exactly, a service optionally followed by ``@gz_request@gz_response``
    (ros_gz_bridge's README, "Bridge communication"). The whole argument, not a part of it: parameter_bridge
    parses the argument as one bridge, so ``'XX/world/...EntityWrenchXX'`` names another topic and another type
    (mutmut held-out seed 43 passed it while the words were searched for)."""
    if not isinstance(argument, str):
        return False
    argument = argument.strip()
    return argument == carried or ("/srv/" in carried and argument.startswith(carried + "@"))


def launch_files(s: Session) -> None:
    """launch_files: the three launch files installed, each starting its node and a ros_gz_bridge
    parameter_bridge that carries what the node talks to (the thrust one on the world's clock)."""
    share = s.find_share(PACKAGE)
    problems = []
    for name, executable, carried in LAUNCH_FILES:
        path = share / "launch" / name if share else None
        if path is None or not path.is_file():
            problems.append(f"{name} not installed")
            continue
        found = launching.read_launch_file(path)
        tree = _parse(path.read_text(encoding="utf-8", errors="replace"))
        # the package may be a name the static reader cannot resolve (PACKAGE = '...'): the executable decides
        nodes = [n for n in found.nodes if n.package in (PACKAGE, None) and n.executable == executable]
        bridges = [n for n in found.nodes if n.package == "ros_gz_bridge" and n.executable == "parameter_bridge"]
        if found.problems:
            problems.append(f"{name}: {found.problems[0]}")
        elif not nodes:
            problems.append(f"{name}: no Node(package='{PACKAGE}', executable='{executable}')")
        elif tree is not None and _node_package(tree, nodes[0].line) not in (PACKAGE, _UNKNOWN):
            problems.append(f"{name}: the Node of {executable} names the package "
                            f"{_node_package(tree, nodes[0].line)!r}, not '{PACKAGE}'")
        elif nodes[0].name not in (None, executable):
            problems.append(f"{name}: the Node of {executable} renames it '{nodes[0].name}' (the contract's node is "
                            f"'{executable}': leave name= out or give that name)")
        elif not bridges:
            problems.append(f"{name}: no Node(package='ros_gz_bridge', executable='parameter_bridge')")
        elif carried.endswith(".yaml"):
            if tree is None or not _sets_config_file(tree):
                problems.append(f"{name}: the bridge has no config_file parameter naming {carried}")
            elif not _names_installed_bridge_file(tree):
                problems.append(f"{name}: the bridge's config_file is not the installed config_bridge/{carried} "
                                f"of {PACKAGE} (the path names {carried} without its config_bridge folder, or in "
                                "another package's share folder)")
            elif not any(isinstance(p, dict) and p.get("use_sim_time") is True for p in nodes[0].parameters):
                problems.append(f"{name}: {executable} without use_sim_time: True")
        elif not any(_bridges(arg, carried) for arg in bridges[0].arguments):
            shown = ", ".join(repr(a) for a in bridges[0].arguments) or "none"
            problems.append(f"{name}: no bridge argument is '{carried}' (its arguments: {shown})")
    s.record("launch_files", not problems, "; ".join(problems) if problems else
             "the three launch files installed, each with its node and its bridge",
             "launch/send_poses_to_gazebo_launch.py, send_wrenches_to_gazebo_launch.py and "
             "control_shape_thrust_launch.py installed in share/" + PACKAGE + "/launch, each a Node of its executable "
             "and a ros_gz_bridge parameter_bridge")


def bridge_config(s: Session) -> None:
    """bridge_config: config_bridge/control_shape_thrust.yaml installed, bridging /clock and the box's pose
    from Gazebo and the wrench topic to it."""
    share = s.find_share(PACKAGE)
    path = share / "config_bridge" / BRIDGE_FILE if share else None
    expected = ("share/" + PACKAGE + f"/config_bridge/{BRIDGE_FILE}: "
                + "; ".join(f"{ros} <- {gz} ({direction})" for ros, gz, _, _, direction in BRIDGE))
    if path is None or not path.is_file():
        s.record("bridge_config", False, f"no config_bridge/{BRIDGE_FILE} installed", expected)
        return
    try:
        entries = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        s.record("bridge_config", False, f"{BRIDGE_FILE} does not load: {str(exc).splitlines()[0]}", expected)
        return
    found = {tuple(str(e.get(key, "")) for key in BRIDGE_KEYS) for e in entries or [] if isinstance(e, dict)}
    missing = [entry for entry in BRIDGE if entry not in found]
    s.record("bridge_config", not missing,
             f"{len(found)} entries; missing: " + "; ".join(f"{ros} ({gz}, {direction})" for ros, gz, _, _, direction
                                                            in missing) if missing else f"{len(found)} entries, all "
             "three bridged the right way", expected)
