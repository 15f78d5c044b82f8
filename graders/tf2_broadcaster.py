"""Grader for ``tf2-broadcaster`` (issue 20; contract in chapters/tf2-broadcaster/CONTRACT.md).

Black-box, on the ``tf2_msgs/msg/TFMessage`` streams the learner's node publishes:

* **broadcaster**: the grader listens on ``/tf`` before the node starts and judges the
  ``world -> robot`` transforms: frame ids, rate (send stamps), the radius and height
  of every position, unit quaternions, the angular speed (a least-squares fit of the
  unwrapped angle over the send stamps), the heading (facing the direction of motion),
  where the angle starts (0 at the node's start) and the header stamps; then a subscription
  made *after* the node has run (a late joiner, TRANSIENT_LOCAL like tf2's own listener)
  must still receive the static ``robot -> camera`` transform on ``/tf_static``, sent once
  (a probe made before the start counts the messages carrying it).
* **cli**: the learner's ``cli/tf2_echo_camera.sh`` runs in a graph of its own where the
  grader broadcasts a static ``robot -> camera`` of random offsets; its output must show
  that offset as ``ros2 run tf2_ros tf2_echo`` prints it, and end by itself after its 3 s.

ROS modules are imported inside the functions that grade: a grader module is also loaded
for its CHECKS alone (``ros2course list``, ``hint``), where ROS is not needed.
"""

from __future__ import annotations

import itertools
import math
import time

from ros2course import kit
from ros2course.kit import LATE_DELIVERY, Check, GradingSession, checks, scripts

PACKAGE = "python_package_that_uses_tf2"
EXE = NODE = "circle_broadcaster"
PARENT, CHILD, CAMERA = "world", "robot", "camera"
RADIUS = 1.0  # metres
ANGULAR_SPEED = 0.5  # rad/s, counter-clockwise (positive)
PERIOD = 0.05  # seconds between transforms (20 Hz)
CAMERA_OFFSET = (0.1, 0.0, 0.2)  # metres, robot -> camera, no rotation
SAMPLES = 20  # transforms judged after the first -> 19 intervals, about 1 s
WARM_UP = 1  # the first transform comes while the process is still starting
START_TIMEOUT = 5.0  # seconds from start to the first transform
#: Tolerances: positions (m) as published with float64 maths; the speed as a rate (±15 %, shared/LESSONS.md);
#: the heading (rad); a quaternion's norm; a header stamp's distance from its send stamp (s).
POSITION_TOLERANCE, SPEED_TOLERANCE, HEADING_TOLERANCE, NORM_TOLERANCE, STAMP_TOLERANCE = 0.01, 0.15, 0.05, 1e-3, 0.5
SCRIPT = "cli/tf2_echo_camera.sh"
SCRIPT_TIMEOUT = 15.0  # seconds: tf2_echo takes about 1 s to start, the script stops it after 3
#: Seconds the script may take in all to count as "tf2_echo for 3 s" (issue 37): 3 s of tf2_echo, the start of
#: `ros2 run` and bash, and slack for a loaded machine; a script that lets tf2_echo run 10 s ends too late.
SCRIPT_LENGTH = 7.0
#: Radians: how far the first angle may fall outside what "0.5 rad/s * seconds since the node started" allows.
ORIGIN_TOLERANCE = 0.05
#: Seconds of observation the contract needs: 21 transforms at 20 Hz, the late joiner's replay.
WINDOW = (WARM_UP + SAMPLES) * PERIOD + 0.5

BROADCASTER = {"part": "broadcaster", "needs": ("broadcaster_executable",)}
MOTION = {"part": "broadcaster", "needs": ("tf_frames",)}
CLI = {"part": "cli", "needs": ("cli_script",)}
QUATERNION_HINT = ("a rotation of yaw about z is the quaternion (0, 0, sin(yaw / 2), cos(yaw / 2)): never write "
                   "the yaw itself into rotation.z")

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("depends", "package.xml depends on rclpy, tf2_ros and geometry_msgs", 1,
          "add <depend>rclpy</depend>, <depend>tf2_ros</depend> and <depend>geometry_msgs</depend> to package.xml"),
    *checks.started("broadcaster", PACKAGE, EXE, NODE, part="broadcaster"),
    Check("tf_frames", f"It broadcasts {PARENT} -> {CHILD} on /tf", 2,
          f"t.header.frame_id = '{PARENT}', t.child_frame_id = '{CHILD}', then TransformBroadcaster.sendTransform(t)",
          **BROADCASTER),
    Check("tf_rate", f"One transform every {PERIOD} s (20 Hz)", 2, f"self.create_timer({PERIOD}, ...)", **MOTION),
    Check("radius", f"The robot stays {RADIUS} m from the origin, in the plane z = 0", 2,
          f"x = {RADIUS} * cos(angle), y = {RADIUS} * sin(angle), z = 0.0", **MOTION),
    Check("unit_quaternion", "Every rotation is a unit quaternion", 1, QUATERNION_HINT, **MOTION),
    Check("angular_speed", f"The robot drives counter-clockwise at {ANGULAR_SPEED} rad/s", 2,
          f"angle = {ANGULAR_SPEED} * seconds since the start (from the node's clock)", **MOTION),
    Check("heading", "The robot faces the direction it drives in (yaw = angle + pi/2)", 1,
          "rotate by yaw = angle + math.pi / 2 about z: " + QUATERNION_HINT, **MOTION),
    Check("starts_at_zero", "The angle counts from the node's start: angle 0 (at x = 1, y = 0) when it starts", 1,
          f"angle = {ANGULAR_SPEED} * (now - self.start) in seconds, with self.start = self.get_clock().now() "
          "taken in __init__: not the clock's own seconds (since 1970), not an offset", **MOTION),
    Check("stamps", "Each transform is stamped with the time it was made (increasing)", 1,
          "t.header.stamp = self.get_clock().now().to_msg() in the timer callback: tf2 looks transforms up by "
          "time", **MOTION),
    Check("static_latched", f"A listener that starts later still gets {CHILD} -> {CAMERA} from /tf_static", 3,
          "StaticTransformBroadcaster(self).sendTransform(...) once: /tf_static is TRANSIENT_LOCAL, so a late "
          "listener receives it; a TransformBroadcaster (/tf) would lose it", **BROADCASTER),
    Check("static_once", f"{CHILD} -> {CAMERA} is sent once, not again and again", 1,
          "build the camera's TransformStamped in __init__ and send it there, once: the publisher keeps it for "
          "every later listener; never in the timer callback", needs=("static_latched",), part="broadcaster"),
    checks.ctrl_c("broadcaster_sigint_exit", "the broadcaster", **BROADCASTER),
    Check("cli_script", f"{SCRIPT} exists and is valid bash", 1, part="cli"),
    Check("cli_echo", f"It prints the transform {CHILD} -> {CAMERA} with tf2_echo", 2,
          f"timeout --signal=INT 3 ros2 run tf2_ros tf2_echo {CHILD} {CAMERA}", **CLI),
    Check("cli_ends", "It ends by itself (tf2_echo stopped after 3 s)", 1,
          "tf2_echo prints until it is stopped: `timeout --signal=INT 3 ros2 run tf2_ros tf2_echo ...` "
          "(a duration of 0 means no timeout at all)", **CLI),
]


def _angle_fit(times: list[float], angles: list[float]) -> float:
    """Least-squares slope (rad/s) of the unwrapped ``angles`` over ``times`` (seconds)."""
    unwrapped = [angles[0]]
    for angle in angles[1:]:
        step = (angle - unwrapped[-1] + math.pi) % (2 * math.pi) - math.pi
        unwrapped.append(unwrapped[-1] + step)
    mean_t, mean_a = sum(times) / len(times), sum(unwrapped) / len(unwrapped)
    spread = sum((t - mean_t) ** 2 for t in times)
    return sum((t - mean_t) * (a - mean_a) for t, a in zip(times, unwrapped)) / spread if spread > 0 else 0.0


def _yaw(q) -> float:
    """Yaw (rad) of quaternion ``q`` (x, y, z, w), about z; the standard ZYX formula."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _grade_broadcaster(s: GradingSession, tf_message: type) -> None:
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    path = kit.executable(s, "broadcaster_executable", PACKAGE, EXE)
    tf = s.graph.topic("/tf", tf_message, 100)
    # every /tf_static message from the node's start on (static_once); static_latched has a late joiner of its own
    early_static = s.graph.topic("/tf_static", tf_message, QoSProfile(
        depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL))
    launched = time.time()  # the node starts after this (send stamps are seconds since the epoch too)
    node = kit.start_node(s, "broadcaster_node_name", path, NODE, sigint_check="broadcaster_sigint_exit",
                          need_node=False)
    with s.phase("observe"):
        window = tf.observe(WARM_UP + SAMPLES, PERIOD, START_TIMEOUT, abort=node.ended)
    samples = tf.samples()[:WARM_UP + SAMPLES]
    stamps = tf.send_stamps(WARM_UP + SAMPLES)
    pairs = sorted({f"{t.header.frame_id} -> {t.child_frame_id}" for _, m in samples for t in m.transforms})
    ours = [(sent, t) for sent, (_, m) in zip(stamps, samples) for t in m.transforms
            if t.header.frame_id == PARENT and t.child_frame_id == CHILD]
    if s.record("tf_frames", bool(ours), f"{len(samples)} message(s) on /tf in {window:.1f} s with "
                f"{', '.join(pairs) or 'no transform'}"
                + ("" if samples else f"; {kit.process_state(node.proc)}"), f"transforms {PARENT} -> {CHILD} on /tf"):
        _judge_motion(s, ours, window, launched)
    if _judge_static(s, tf, node, tf_message):
        _judge_static_once(s, early_static)


def _judge_motion(s: GradingSession, ours: list, window: float, launched: float) -> None:
    """tf_rate, radius, unit_quaternion, angular_speed, heading, starts_at_zero, stamps over ``ours``.

    ``ours``: (send stamp, transform); ``launched``: when the grader started the process (seconds since the epoch).
    """
    kit.rate(s, "tf_rate", [sent for sent, _ in ours][WARM_UP:], period=PERIOD, needed=SAMPLES, waited=window,
             noun="transform", source=f"the send stamps of the {PARENT} -> {CHILD} messages, the first left out")
    moves = [t.transform for _, t in ours]
    distances = [math.hypot(m.translation.x, m.translation.y) for m in moves]
    heights = [abs(m.translation.z) for m in moves]
    worst = max(abs(d - RADIUS) for d in distances)
    s.record("radius", worst <= POSITION_TOLERANCE and max(heights) <= POSITION_TOLERANCE,
             f"distance from the origin {min(distances):.3f} to {max(distances):.3f} m, |z| up to {max(heights):.3f} m "
             f"over {len(moves)} transforms", f"{RADIUS} m ± {POSITION_TOLERANCE} m in the plane z = 0")
    norms = [math.sqrt(m.rotation.x ** 2 + m.rotation.y ** 2 + m.rotation.z ** 2 + m.rotation.w ** 2) for m in moves]
    off = max(abs(n - 1.0) for n in norms)
    s.record("unit_quaternion", off <= NORM_TOLERANCE,
             f"quaternion norms {min(norms):.4f} to {max(norms):.4f}", f"1 ± {NORM_TOLERANCE} (a unit quaternion)")
    angles = [math.atan2(m.translation.y, m.translation.x) for m in moves]
    speed = _angle_fit([sent for sent, _ in ours], angles) if len(ours) > 2 else 0.0
    s.record("angular_speed", abs(speed - ANGULAR_SPEED) <= SPEED_TOLERANCE * ANGULAR_SPEED,
             f"{speed:.3f} rad/s (least-squares slope of the angle atan2(y, x) over the send stamps, "
             f"{len(ours)} transforms)", f"{ANGULAR_SPEED} rad/s ± {SPEED_TOLERANCE:.0%}, counter-clockwise")
    # the heading is judged only where the rotation is a rotation (a unit quaternion), else unit_quaternion says it
    errors = [abs((_yaw(m.rotation) - (a + math.pi / 2) + math.pi) % (2 * math.pi) - math.pi)
              for m, a, n in zip(moves, angles, norms) if abs(n - 1.0) <= 0.1]
    s.record("heading", bool(errors) and max(errors) <= HEADING_TOLERANCE,
             f"yaw - (angle + pi/2) up to {max(errors):.3f} rad" if errors else "no rotation is a unit quaternion",
             f"yaw = atan2(y, x) + pi/2 ± {HEADING_TOLERANCE} rad")
    _judge_origin(s, ours[0][0], angles[0], launched)
    headers = [t.header.stamp.sec + t.header.stamp.nanosec * 1e-9 for _, t in ours]
    backwards = sum(1 for a, b in itertools.pairwise(headers) if b <= a)
    away = max(abs(h - sent) for h, (sent, _) in zip(headers, ours))
    s.record("stamps", not backwards and away <= STAMP_TOLERANCE,
             "every header.stamp is 0 (never set)" if not any(headers) else
             f"{backwards} of {len(headers) - 1} stamps not later than the previous one; up to {away:.3f} s from "
             "when the message was sent",
             f"increasing stamps, each within {STAMP_TOLERANCE} s of when its message was sent")



def _judge_origin(s: GradingSession, sent: float, angle: float, launched: float) -> None:
    """starts_at_zero: angle = 0.5 rad/s * seconds since the node started, so at the first transform (sent at
    ``sent``, at ``angle`` = atan2(y, x)) it lies between 0 (the node started just before) and 0.5 * (sent -
    ``launched``) (the node started as the process did): a clock's own seconds, or an offset, land elsewhere.
    """
    most = ANGULAR_SPEED * max(0.0, sent - launched)
    wrapped = (angle + math.pi) % (2 * math.pi) - math.pi  # in [-pi, pi)
    s.record("starts_at_zero", -ORIGIN_TOLERANCE <= wrapped <= most + ORIGIN_TOLERANCE,
             f"the first transform, {sent - launched:.2f} s after the process was started, is at angle {wrapped:.3f} rad",
             f"an angle in [0, {most:.3f}] rad ± {ORIGIN_TOLERANCE} ({ANGULAR_SPEED} rad/s * the seconds the node has "
             "run, which are fewer than the process has): the robot starts at (1, 0)")


def _judge_static_once(s: GradingSession, early) -> None:
    """static_once: the node's /tf_static messages carrying robot -> camera, from its start to now: one."""
    carrying = [m for m in early.messages()
                if any(t.header.frame_id == CHILD and t.child_frame_id == CAMERA for t in m.transforms)]
    s.record("static_once", len(carrying) == 1,
             f"{len(carrying)} message(s) on /tf_static carried {CHILD} -> {CAMERA} while the grader listened, from "
             "before the node started until the late listener got it",
             "one message: the static transform is sent once (TRANSIENT_LOCAL keeps it for later listeners)")


def _judge_static(s: GradingSession, tf, node, tf_message: type) -> bool:
    """static_latched: a late TRANSIENT_LOCAL subscription gets robot -> camera (``tf``: the /tf probe)."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    # a late joiner, as tf2's TransformListener subscribes: RELIABLE, TRANSIENT_LOCAL
    late = s.graph.topic("/tf_static", tf_message, QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                                                              durability=DurabilityPolicy.TRANSIENT_LOCAL))
    with s.phase("observe"):
        late.wait_for_count(1, LATE_DELIVERY + 1.0, abort=node.ended)
    static = [t for m in late.messages() for t in m.transforms]
    camera = [t for t in static if t.header.frame_id == CHILD and t.child_frame_id == CAMERA]
    on_tf = sorted({t.child_frame_id for _, m in tf.samples() for t in m.transforms if t.child_frame_id == CAMERA})
    expected = (f"{CHILD} -> {CAMERA} at ({', '.join(f'{v:g}' for v in CAMERA_OFFSET)}) m, no rotation, "
                "received by a TRANSIENT_LOCAL subscription made after the node started")
    if not camera:
        seen = ", ".join(f"{t.header.frame_id} -> {t.child_frame_id}" for t in static) or "nothing"
        return s.record("static_latched", False, f"a late subscription to /tf_static received {seen}"
                        + (f"; {CAMERA} came on /tf instead (a TransformBroadcaster: volatile, a late listener never "
                           "gets it)" if on_tf else ""), expected)
    t = camera[-1].transform
    found = (t.translation.x, t.translation.y, t.translation.z)
    rotation = (t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w)
    return s.record("static_latched", all(abs(a - b) <= POSITION_TOLERANCE for a, b in zip(found, CAMERA_OFFSET))
             and all(abs(a - b) <= NORM_TOLERANCE for a, b in zip(rotation, (0.0, 0.0, 0.0, 1.0))),
             f"a late subscription to /tf_static received {CHILD} -> {CAMERA} at "
             f"({', '.join(f'{v:.3f}' for v in found)}) m, rotation ({', '.join(f'{v:.3f}' for v in rotation)})",
             expected)


def _grade_cli(s: GradingSession, tf_message: type) -> None:
    from geometry_msgs.msg import TransformStamped  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    path = scripts.script(s, "cli_script", SCRIPT)
    offset = tuple(round(s.random.uniform(*bounds), 3) for bounds in ((0.2, 0.9), (-0.9, -0.2), (0.2, 0.9)))
    t = TransformStamped()
    t.header.stamp = s.graph.node.get_clock().now().to_msg()
    t.header.frame_id, t.child_frame_id = CHILD, CAMERA
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = offset
    t.transform.rotation.w = 1.0
    # what tf2_ros.StaticTransformBroadcaster does (tf2_ros/static_transform_broadcaster.py), without importing
    # tf2_ros into the grader (its C extension needs the underlay's libtf2 on the process's library path):
    # one TFMessage on /tf_static, latched, so tf2_echo receives it whenever it starts
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    s.graph.node.create_publisher(tf_message, "/tf_static", latched).publish(tf_message(transforms=[t]))
    run = scripts.run_script(s, path, timeout=SCRIPT_TIMEOUT)
    shown = f"- Translation: [{offset[0]:.3f}, {offset[1]:.3f}, {offset[2]:.3f}]"
    scripts.printed(s, "cli_echo", run, [shown], f"the grader's {CHILD} -> {CAMERA} transform ({shown[2:]})",
                    f"ros2 run tf2_ros tf2_echo {CHILD} {CAMERA}")
    # the lesson's script "ends by itself" (an exit code is not asked for: `timeout` itself exits 124)
    # "tf2_echo ... for 3 s" (issue 37): it must also end soon after those 3 s, not after 10
    s.record("cli_ends", not run.timed_out and run.seconds <= SCRIPT_LENGTH,
             f"your script was still running after {SCRIPT_TIMEOUT:.0f} s and was stopped ({run.describe()})"
             if run.timed_out else f"it ended by itself after {run.seconds:.1f} s: {run.describe()}",
             f"the script ends by itself after about 3 s of tf2_echo (within {SCRIPT_LENGTH:.0f} s in all)")


def grade(s: GradingSession) -> None:
    """The broadcaster, then the script in a graph of its own (see the module docstring)."""
    kit.depends(s, "depends", PACKAGE, ("rclpy", "tf2_ros", "geometry_msgs"))
    tf_message = s.installed_type("tf2_msgs", "msg", "TFMessage")  # tf2 is not on PyPI: from the underlay
    with s.part("broadcaster"):
        _grade_broadcaster(s, tf_message)
    with s.part("cli", own_graph=True):
        _grade_cli(s, tf_message)
