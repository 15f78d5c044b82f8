"""The tf2-broadcaster lesson's judgements (graders/tf2_broadcaster.py declares the checks and the contract).

One function per check, or per group of checks judged on the same observation: the ``world -> robot``
transforms a node broadcasts on ``/tf`` (frames, rate, radius, quaternions, angular speed, heading, start
angle, header stamps), the static ``robot -> camera`` transform on ``/tf_static`` (a late joiner receives it;
it is sent once), and the grader's own static transform for the lesson's ``tf2_echo`` script. Each function
records the check ids its docstring names; the numbers come from a :class:`Circle` the grader declares.

The QoS of ``/tf_static`` (RELIABLE, TRANSIENT_LOCAL: what tf2_ros's StaticTransformBroadcaster and its
listeners use, tf2_ros/qos.py) is built here from rclpy, without importing tf2_ros (its C extension needs the
underlay's libtf2 on the process's library path).

ROS modules are imported inside the functions that grade: a grader module is also loaded
for its CHECKS alone (``ros2course list``, ``hint``), where ROS is not needed.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from typing import Any

from ros2course import kit
from ros2course.kit import LATE_DELIVERY, Session


@dataclasses.dataclass(frozen=True)
class Circle:
    """What the lesson's node must broadcast, and the tolerances it is judged with.

    Frames: ``parent -> child`` on /tf, ``child -> camera`` on /tf_static. Units: metres (``radius``,
    ``camera_offset``, ``position_tolerance``), rad/s (``angular_speed``, counter-clockwise positive), seconds
    (``period`` between transforms, ``start_timeout`` from the start to the first transform,
    ``stamp_tolerance`` between a header stamp and its send stamp), radians (``heading_tolerance``,
    ``origin_tolerance``); ``speed_tolerance`` is a fraction of ``angular_speed``, ``norm_tolerance`` the
    distance of a quaternion's norm from 1. ``warm_up`` transforms are left out, ``samples`` judged after them.
    """

    parent: str
    child: str
    camera: str
    radius: float
    angular_speed: float
    period: float
    camera_offset: tuple[float, float, float]
    samples: int
    warm_up: int
    start_timeout: float
    position_tolerance: float
    speed_tolerance: float
    heading_tolerance: float
    norm_tolerance: float
    stamp_tolerance: float
    origin_tolerance: float


def static_qos(depth: int) -> Any:
    """``rclpy.qos.QoSProfile``: keep-last ``depth``, RELIABLE, TRANSIENT_LOCAL (the QoS of tf2's /tf_static)."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    return QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


def angle_fit(times: list[float], angles: list[float]) -> float:
    """Least-squares slope (rad/s) of the unwrapped ``angles`` (radians) over ``times`` (seconds); 0.0 when all
    ``times`` are equal."""
    unwrapped = [angles[0]]
    for angle in angles[1:]:
        step = (angle - unwrapped[-1] + math.pi) % (2 * math.pi) - math.pi
        unwrapped.append(unwrapped[-1] + step)
    mean_t, mean_a = sum(times) / len(times), sum(unwrapped) / len(unwrapped)
    spread = sum((t - mean_t) ** 2 for t in times)
    return sum((t - mean_t) * (a - mean_a) for t, a in zip(times, unwrapped)) / spread if spread > 0 else 0.0


def yaw(q) -> float:
    """Yaw (rad) of quaternion ``q`` (x, y, z, w), about z; the standard ZYX formula."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def frames(s: Session, c: Circle, tf, node) -> tuple[bool, list, float]:
    """tf_frames: observe ``c.warm_up + c.samples`` messages on the /tf probe ``tf`` (a TopicProbe made before
    ``node``, a :class:`~ros2course.kit.StartedNode`, started) and judge whether ``parent -> child`` is among them.

    Returns:
        whether tf_frames passed; the (send stamp in seconds since the epoch, transform) pairs of
        ``parent -> child``; the window observed, in seconds.
    """
    with s.phase("observe"):
        window = tf.observe(c.warm_up + c.samples, c.period, c.start_timeout, abort=node.ended)
    samples = tf.samples()[:c.warm_up + c.samples]
    stamps = tf.send_stamps(c.warm_up + c.samples)
    pairs = sorted({f"{t.header.frame_id} -> {t.child_frame_id}" for _, m in samples for t in m.transforms})
    ours = [(sent, t) for sent, (_, m) in zip(stamps, samples) for t in m.transforms
            if t.header.frame_id == c.parent and t.child_frame_id == c.child]
    found = s.record("tf_frames", bool(ours), f"{len(samples)} message(s) on /tf in {window:.1f} s with "
                     f"{', '.join(pairs) or 'no transform'}" + ("" if samples else f"; {kit.process_state(node.proc)}"),
                     f"transforms {c.parent} -> {c.child} on /tf")
    return found, ours, window


def motion(s: Session, c: Circle, ours: list, window: float, launched: float) -> None:
    """tf_rate, radius, unit_quaternion, angular_speed, heading, starts_at_zero, stamps over ``ours``.

    ``ours``: (send stamp, transform) pairs from :func:`frames`, at least one; ``window``: the seconds observed;
    ``launched``: when the grader started the process (seconds since the epoch).
    """
    kit.rate(s, "tf_rate", [sent for sent, _ in ours][c.warm_up:], period=c.period, needed=c.samples,
             waited=window, noun="transform",
             source=f"the send stamps of the {c.parent} -> {c.child} messages, the first left out")
    moves = [t.transform for _, t in ours]
    distances = [math.hypot(m.translation.x, m.translation.y) for m in moves]
    heights = [abs(m.translation.z) for m in moves]
    worst = max(abs(d - c.radius) for d in distances)
    s.record("radius", worst <= c.position_tolerance and max(heights) <= c.position_tolerance,
             f"distance from the origin {min(distances):.3f} to {max(distances):.3f} m, |z| up to {max(heights):.3f} m "
             f"over {len(moves)} transforms", f"{c.radius} m ± {c.position_tolerance} m in the plane z = 0")
    norms = [math.sqrt(m.rotation.x ** 2 + m.rotation.y ** 2 + m.rotation.z ** 2 + m.rotation.w ** 2) for m in moves]
    off = max(abs(n - 1.0) for n in norms)
    s.record("unit_quaternion", off <= c.norm_tolerance,
             f"quaternion norms {min(norms):.4f} to {max(norms):.4f}", f"1 ± {c.norm_tolerance} (a unit quaternion)")
    angles = [math.atan2(m.translation.y, m.translation.x) for m in moves]
    speed = angle_fit([sent for sent, _ in ours], angles) if len(ours) > 2 else 0.0
    s.record("angular_speed", abs(speed - c.angular_speed) <= c.speed_tolerance * c.angular_speed,
             f"{speed:.3f} rad/s (least-squares slope of the angle atan2(y, x) over the send stamps, "
             f"{len(ours)} transforms)", f"{c.angular_speed} rad/s ± {c.speed_tolerance:.0%}, counter-clockwise")
    # the heading is judged only where the rotation is a rotation (a unit quaternion), else unit_quaternion says it
    errors = [abs((yaw(m.rotation) - (a + math.pi / 2) + math.pi) % (2 * math.pi) - math.pi)
              for m, a, n in zip(moves, angles, norms) if abs(n - 1.0) <= 0.1]
    s.record("heading", bool(errors) and max(errors) <= c.heading_tolerance,
             f"yaw - (angle + pi/2) up to {max(errors):.3f} rad" if errors else "no rotation is a unit quaternion",
             f"yaw = atan2(y, x) + pi/2 ± {c.heading_tolerance} rad")
    origin(s, c, ours[0][0], angles[0], launched)
    headers = [t.header.stamp.sec + t.header.stamp.nanosec * 1e-9 for _, t in ours]
    backwards = sum(1 for a, b in itertools.pairwise(headers) if b <= a)
    away = max(abs(h - sent) for h, (sent, _) in zip(headers, ours))
    s.record("stamps", not backwards and away <= c.stamp_tolerance,
             "every header.stamp is 0 (never set)" if not any(headers) else
             f"{backwards} of {len(headers) - 1} stamps not later than the previous one; up to {away:.3f} s from "
             "when the message was sent",
             f"increasing stamps, each within {c.stamp_tolerance} s of when its message was sent")


def origin(s: Session, c: Circle, sent: float, angle: float, launched: float) -> None:
    """starts_at_zero: angle = 0.5 rad/s * seconds since the node started, so at the first transform (sent at
    ``sent``, at ``angle`` = atan2(y, x)) it lies between 0 (the node started just before) and 0.5 * (sent -
    ``launched``) (the node started as the process did): a clock's own seconds, or an offset, land elsewhere.
    ``sent`` and ``launched`` are seconds since the epoch, ``angle`` radians.
    """
    most = c.angular_speed * max(0.0, sent - launched)
    wrapped = (angle + math.pi) % (2 * math.pi) - math.pi  # in [-pi, pi)
    s.record("starts_at_zero", -c.origin_tolerance <= wrapped <= most + c.origin_tolerance,
             f"the first transform, {sent - launched:.2f} s after the process was started, is at angle {wrapped:.3f} rad",
             f"an angle in [0, {most:.3f}] rad ± {c.origin_tolerance} ({c.angular_speed} rad/s * the seconds the node "
             "has run, which are fewer than the process has): the robot starts at (1, 0)")


def static_latched(s: Session, c: Circle, tf, node, tf_message: type) -> bool:
    """static_latched: a late TRANSIENT_LOCAL subscription gets ``child -> camera`` at ``c.camera_offset``, no
    rotation (``tf``: the /tf probe, to say when the camera came on /tf instead; ``node``: the started node;
    ``tf_message``: ``tf2_msgs/msg/TFMessage``). Waits up to LATE_DELIVERY + 1 s; returns the verdict."""
    # a late joiner, as tf2's TransformListener subscribes: RELIABLE, TRANSIENT_LOCAL
    late = s.graph.topic("/tf_static", tf_message, static_qos(10))
    with s.phase("observe"):
        late.wait_for_count(1, LATE_DELIVERY + 1.0, abort=node.ended)
    static = [t for m in late.messages() for t in m.transforms]
    camera = [t for t in static if t.header.frame_id == c.child and t.child_frame_id == c.camera]
    on_tf = sorted({t.child_frame_id for _, m in tf.samples() for t in m.transforms if t.child_frame_id == c.camera})
    expected = (f"{c.child} -> {c.camera} at ({', '.join(f'{v:g}' for v in c.camera_offset)}) m, no rotation, "
                "received by a TRANSIENT_LOCAL subscription made after the node started")
    if not camera:
        seen = ", ".join(f"{t.header.frame_id} -> {t.child_frame_id}" for t in static) or "nothing"
        return s.record("static_latched", False, f"a late subscription to /tf_static received {seen}"
                        + (f"; {c.camera} came on /tf instead (a TransformBroadcaster: volatile, a late listener "
                           "never gets it)" if on_tf else ""), expected)
    t = camera[-1].transform
    found = (t.translation.x, t.translation.y, t.translation.z)
    rotation = (t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w)
    return s.record("static_latched", all(abs(a - b) <= c.position_tolerance for a, b in zip(found, c.camera_offset))
                    and all(abs(a - b) <= c.norm_tolerance for a, b in zip(rotation, (0.0, 0.0, 0.0, 1.0))),
                    f"a late subscription to /tf_static received {c.child} -> {c.camera} at "
                    f"({', '.join(f'{v:.3f}' for v in found)}) m, rotation ({', '.join(f'{v:.3f}' for v in rotation)})",
                    expected)


def static_once(s: Session, c: Circle, early) -> None:
    """static_once: the node's /tf_static messages carrying ``child -> camera``, from its start to now, on the
    probe ``early`` (made before the node started, :func:`static_qos`): one."""
    carrying = [m for m in early.messages()
                if any(t.header.frame_id == c.child and t.child_frame_id == c.camera for t in m.transforms)]
    s.record("static_once", len(carrying) == 1,
             f"{len(carrying)} message(s) on /tf_static carried {c.child} -> {c.camera} while the grader listened, "
             "from before the node started until the late listener got it",
             "one message: the static transform is sent once (TRANSIENT_LOCAL keeps it for later listeners)")


def broadcast_static(s: Session, tf_message: type, parent: str, child: str,
                     offset: tuple[float, float, float]) -> None:
    """Send ``parent -> child`` at ``offset`` (metres), no rotation, stamped now, from the grader's node of
    ``s.graph``: what tf2_ros.StaticTransformBroadcaster does (tf2_ros/static_transform_broadcaster.py), one
    TFMessage (``tf_message``) on /tf_static, latched (:func:`static_qos` of depth 1), so a tf2 listener
    receives it whenever it starts."""
    from geometry_msgs.msg import TransformStamped  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    t = TransformStamped()
    t.header.stamp = s.graph.node.get_clock().now().to_msg()
    t.header.frame_id, t.child_frame_id = parent, child
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = offset
    t.transform.rotation.w = 1.0
    s.graph.node.create_publisher(tf_message, "/tf_static", static_qos(1)).publish(tf_message(transforms=[t]))
