"""Grader for ``sas-robot-driver`` (seed ch. 29-31; contract in shared/LESSONS.md, sas facts in ROS_ENV.md).

Black-box (graders/kit/sas.py), so the same grader judges the Python driver
of the lesson and the seed's C++ driver built on the real ``sas`` packages:
the installed launch file (read statically); the driver started as launch_ros
starts its ``Node`` action with the seed's parameters (ch. 31.7): its 500 Hz
joint states, limits in radians, how fast it follows targets, a target of the
wrong size, Ctrl+C; the driver again, renamed myrobot_2 with other limits and another period (its prefix and
values must be read, not typed); the client in a graph of its own where the grader plays
the driver (silent until enabled, 100 Hz, within 10 degrees, moving, Ctrl+C).
"""

from __future__ import annotations

import math

from ros2course import kit
from ros2course.kit import Check, Session, Unmet, checks, params
from . import _sas as sas

PACKAGE = "sas_robot_driver_myrobot"
DRIVER_EXECUTABLE = "sas_robot_driver_myrobot_node"
CLIENT_EXECUTABLE = "joint_interface_example"
NODE = "myrobot_1"
LAUNCH_FILE = "real_robot_launch.py"
#: The seed's launch file parameters (ch. 31.7); limits in degrees, 500 Hz loop.
DRIVER = sas.SasDriver(PACKAGE, DRIVER_EXECUTABLE, NODE, {
    "ip": "127.0.0.1",
    "joint_limits_min": [-360.0, -360.0, -360.0, -360.0, -360.0, -720.0],
    "joint_limits_max": [360.0, 360.0, 360.0, 360.0, 360.0, 720.0],
    "thread_sampling_time_sec": 0.002,
})
#: The same driver as another launch file could start it: another name (the topics' prefix) and other parameters
#: (limits of 90 and 180 degrees, a 250 Hz loop), so the prefix and the values must be read, not typed.
RENAMED = sas.SasDriver(PACKAGE, DRIVER_EXECUTABLE, "myrobot_2", {
    "ip": "127.0.0.1",
    "joint_limits_min": [-90.0, -90.0, -90.0, -90.0, -90.0, -180.0],
    "joint_limits_max": [90.0, 90.0, 90.0, 90.0, 90.0, 180.0],
    "thread_sampling_time_sec": 0.004,
})
RATE_SPAN = 1.0  # seconds of stream the rate is measured over (500 intervals at 500 Hz)
#: Joint targets (radians) sent in turn; all inside the limits, every joint different.
TARGETS = [
    [0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
    [-0.5, 0.25, -1.0, 1.5, -0.75, 3.0],
    [0.0, -0.3, 0.6, -0.9, 1.2, -1.5],
]
TRACK_LATENCY = 0.1  # seconds: the stream shows a target this soon after it is sent
TRACK_GIVE_UP = 0.5  # seconds waited per target before calling it not followed
RESEND = 0.01  # seconds between repeated publications of a target (a client streams them too)
#: Targets of the wrong size, sent in turn: five values and seven (a size check written `<` or `>` lets one
#: through); neither may ever be applied.
WRONG_TARGETS = ([0.7] * 5, [0.7] * 7)
WRONG_WATCH = 0.3  # seconds the stream is watched after each wrong-size target
CLIENT_PERIOD = 0.01  # seconds: the client sends a target every 10 ms (seed ch. 31.9)
CLIENT_AMPLITUDE = math.radians(10.0)  # radians around the initial positions (seed ch. 31.9)
CLIENT_MIN_SWING = math.radians(1.0)  # radians each joint must move over the window to count as moving
CLIENT_STEP = 1.0 / (50.0 * math.pi)  # radians of sin's argument per loop iteration (seed ch. 31.9)
#: Radians RMS from that law, i known from the sequence numbers: a client that follows the law is within float
#: rounding (1e-7 degrees), another divisor than 50 * pi is not (51: 0.04 degrees; held-out seed 28 left it alive
#: under the earlier 0.2 degrees, which a phase grid of 0.5 degrees needed).
CLIENT_LAW_TOLERANCE = math.radians(0.01)
#: Radians RMS when the middleware gives no sequence numbers and i is the targets' order: a target the reader
#: missed shifts the later ones by one step (0.06 degrees).
CLIENT_LAW_TOLERANCE_UNNUMBERED = math.radians(0.2)
#: Radians the law's phase may lie from the one the targets' sequence numbers give (i = 0 at the first): a loop
#: counted from 1 is one step (0.006) off; the other sign (-sin) is pi off.
CLIENT_LAW_PHASE_SLACK = math.pi / 4
CLIENT_DISABLED = 0.5  # seconds of joint states without limits: the client must stay silent
CLIENT_WINDOW = 1.5  # seconds of targets judged
CLIENT_STREAM_PERIOD = 0.01  # seconds between the stand-in driver's joint states
#: The stand-in driver's joint positions (radians): not zeros, so a client must read them.
INITIAL = [0.1, -0.2, 0.3, 0.4, -0.5, 0.6]
#: Seconds of observation: stream rate, target tracking, wrong-size watch, the renamed driver's half second of
#: stream, client silent + client targets.
WINDOW = (RATE_SPAN + len(TARGETS) * TRACK_LATENCY + len(WRONG_TARGETS) * WRONG_WATCH + 0.5 + CLIENT_DISABLED
          + CLIENT_WINDOW)
TARGET_TOPIC = DRIVER.target
DRIVER_PART = {"needs": ("executable",), "part": "driver"}
CLIENT_PART = {"needs": ("client_executable",), "part": "client"}

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("launch_file", f"launch/{LAUNCH_FILE} is installed and starts the driver as {NODE} with the seed's "
          "parameters", 2,
          "install launch/*_launch.py from setup.py's data_files to share/<package>/launch, and give Node(...) "
          f"package='{PACKAGE}', executable='{DRIVER_EXECUTABLE}', name='{NODE}' and the parameters of ch. 31.7"),
    Check("executable", f"ros2 run finds {DRIVER_EXECUTABLE}", 1,
          f"add '{DRIVER_EXECUTABLE} = {PACKAGE}.{DRIVER_EXECUTABLE}:main' to console_scripts in setup.py",
          part="driver"),
    Check("driver_starts", f"The driver runs as node {NODE}", 1,
          "create one Node in main() and do not exit: a missing parameter or an exception in __init__ ends it",
          **DRIVER_PART),
    Check("declares_parameters", "It declares ip, joint_limits_min, joint_limits_max and thread_sampling_time_sec "
          "(ros2 param list)", 1,
          "read every parameter with get_ros_parameter(node, name, type), which declares it: a value typed in "
          "the code (ip = '127.0.0.1') leaves the launch file's parameter undeclared", **DRIVER_PART),
    Check("interface", f"It has the sas topics under /{NODE}/", 2,
          "use the node's name as the prefix: f'{node.get_name()}/get/joint_states' and so on (ROS_ENV.md list)",
          **DRIVER_PART),
    Check("stream_rate", "Joint states stream at 500 Hz (every thread_sampling_time_sec)", 3,
          "run the loop with self.create_timer(thread_sampling_time_sec, ...) and read the parameter, "
          "do not hard-code another period", **DRIVER_PART),
    Check("stream_shape", "Each joint state has 6 positions and an increasing stamp", 2,
          "fill msg.position with the 6 joint positions and msg.header.stamp with node.get_clock().now().to_msg()",
          **DRIVER_PART),
    Check("zeros_at_start", "The positions are zeros after connect()", 1,
          "connect() sets the joint positions to six zeros, as the seed's driver does", **DRIVER_PART),
    Check("limits_published", "Both limits topics are published (6 values each)", 2,
          "publish get/joint_positions_min and get/joint_positions_max in every loop, like sas does", **DRIVER_PART),
    Check("limits_radians", "The limits are the parameters converted to radians", 2,
          "the parameters are in degrees: convert with numpy.deg2rad before publishing",
          needs=("limits_published",), part="driver"),
    Check("tracking", f"The stream follows each target within {TRACK_LATENCY:.1f} s", 3,
          "store the latest target in the subscriber callback and apply it with set_target_joint_positions "
          "in the next loop iteration", **DRIVER_PART),
    Check("wrong_size", "A target of the wrong size (5 or 7 values) is not applied (error logged)", 2,
          "set_target_joint_positions must raise on a vector whose size is not 6; catch it in the loop, log "
          "an error and keep the previous positions (or end cleanly, as sas does)", **DRIVER_PART),
    checks.ctrl_c("sigint_exit", "the driver", 2,
                  "catch (KeyboardInterrupt, ExternalShutdownException) around the loop, then deinitialize() and "
                  "disconnect() in finally", **DRIVER_PART),
    Check("prefix_from_name", f"Started as {RENAMED.node} (renamed, as a launch file may), its topics are under "
          f"/{RENAMED.node}/", 2, "build the driver and RobotDriverROS with the prefix node.get_name(), never a typed "
          "'myrobot_1'", needs=("driver_starts",), part="renamed"),
    Check("limits_from_parameters", "With other joint_limits_min / joint_limits_max, it publishes those (in radians)",
          1, "read the limits with get_parameter (declare_parameter(...).value), never type the seed's values",
          needs=("prefix_from_name",), part="renamed"),
    Check("period_from_parameter", "With another thread_sampling_time_sec (0.004 s), it streams at that period", 1,
          "create the loop's timer with the parameter's value, not a typed 0.002", needs=("prefix_from_name",),
          part="renamed"),
    Check("client_executable", f"ros2 run finds {CLIENT_EXECUTABLE}", 1,
          f"add '{CLIENT_EXECUTABLE} = {PACKAGE}.{CLIENT_EXECUTABLE}:main' to console_scripts in setup.py",
          part="client"),
    Check("client_waits", "The client sends nothing before the driver is enabled", 2,
          "loop on rdi.is_enabled() (joint states AND both limits received) before reading positions", **CLIENT_PART),
    Check("client_topic", f"The client is the one publisher of Float64MultiArray on {TARGET_TOPIC}", 1,
          "send targets with one publisher on 'myrobot_1/set/target_joint_positions' (RobotDriverClient)",
          **CLIENT_PART),
    Check("client_rate", "The client sends a target every 10 ms (100 Hz)", 2,
          "use Clock(0.01): clock.update_and_sleep() once per loop iteration", **CLIENT_PART),
    Check("client_targets", "Targets have 6 values within 10 degrees of the initial positions", 2,
          "target = joint_positions + numpy.deg2rad([10.0 * sin(...)] * 6), with joint_positions read once "
          "after the driver is enabled", **CLIENT_PART),
    Check("client_swing", "The targets swing as the seed's loop does: 10 * sin(i / (50 * pi)) degrees", 1,
          "target = joint_positions + numpy.deg2rad([10.0 * sin(i / (50.0 * pi))] * 6), i counting the loop's "
          "iterations from 0, one target per iteration", **CLIENT_PART),
    Check("client_moves", "Every joint of the targets actually moves", 1,
          "make the offset depend on the loop counter i, e.g. 10.0 * sin(i / (50.0 * pi)) degrees", **CLIENT_PART),
    checks.ctrl_c("client_sigint_exit", "the client", 1,
                  "wrap main() in try: ... except (KeyboardInterrupt, ExternalShutdownException): pass, with "
                  "rclpy.try_shutdown() in finally: after Ctrl+C, spin_once and send_target_joint_positions "
                  "raise ExternalShutdownException", **CLIENT_PART),
]


def grade(s: Session) -> None:
    """Check the launch file, grade the driver, then the client (started first, in a graph of its own)."""
    sas.launch_file(s, "launch_file", DRIVER, LAUNCH_FILE)
    client = None
    with s.part("client"):  # starts now: its start-up overlaps the driver's grading; the two never meet
        client = sas.start_client(s, "client_executable", DRIVER, CLIENT_EXECUTABLE, initial=INITIAL,
                                  period=CLIENT_STREAM_PERIOD, sigint_check="client_sigint_exit")
    with s.part("driver"):
        kit.executable(s, "executable", PACKAGE, DRIVER_EXECUTABLE)
        driver = sas.start_driver(s, "driver_starts", DRIVER, sigint_check="sigint_exit")
        declares_parameters(s, "declares_parameters", driver)
        sas.interface(s, "interface", driver)
        sas.limits(s, "limits_published", "limits_radians", driver)
        sas.stream(s, "stream_rate", "stream_shape", "zeros_at_start", driver, span=RATE_SPAN)
        followed = sas.tracking(s, "tracking", driver, TARGETS, latency=TRACK_LATENCY, give_up=TRACK_GIVE_UP,
                                resend=RESEND)
        sas.wrong_size(s, "wrong_size", driver, WRONG_TARGETS, followed, watch=WRONG_WATCH, resend=RESEND)
        sas.plot_stream(s, driver)
    with s.part("renamed"):  # after the driver part: its run has had its Ctrl+C
        s.require("driver_starts")
        sas.renamed(s, "prefix_from_name", "limits_from_parameters", "period_from_parameter", RENAMED)
    with s.part("client"):
        s.require("client_executable")
        s.on_close(lambda: client.close(s))
        sas.client_waits(s, "client_waits", client, CLIENT_DISABLED)
        targets = sas.client_targets(s, "client_topic", client, CLIENT_WINDOW)
        sas.span_rate(s, "client_rate", targets, period=CLIENT_PERIOD, span=CLIENT_WINDOW, noun="target",
                      extra=" (like ros2 topic hz, over the DDS source timestamps)",
                      few_note=f"; {kit.process_state(client.proc)}")
        sas.client_offsets(s, "client_targets", "client_moves", client, targets, amplitude=CLIENT_AMPLITUDE,
                           min_swing=CLIENT_MIN_SWING, window=CLIENT_WINDOW, label=CLIENT_EXECUTABLE)
        sas.client_swing(s, "client_swing", client, targets, amplitude=CLIENT_AMPLITUDE, step=CLIENT_STEP,
                         tolerance=CLIENT_LAW_TOLERANCE, unnumbered_tolerance=CLIENT_LAW_TOLERANCE_UNNUMBERED,
                         phase_slack=CLIENT_LAW_PHASE_SLACK)


def declares_parameters(s: Session, check_id: str, run: sas.DriverRun) -> None:
    """Record ``check_id``: ``ros2 param list /myrobot_1`` has every parameter of the launch file (seed ch. 31.7:
    the driver reads ip, joint_limits_min, joint_limits_max and thread_sampling_time_sec with sas's
    get_ros_parameter, which declares each). Only the names: a parameter declared with another type than the
    launch file's value ends the node as it starts (driver_starts), and ip's value changes nothing the driver
    shows (the lesson's robot is simulated)."""
    wanted = list(run.driver.parameters)
    try:
        names = params.connect(s, run.driver.node, proc=run.proc).names()
    except Unmet as exc:
        s.record(check_id, False, str(exc), f"{', '.join(wanted)} declared")
        return
    missing = [name for name in wanted if name not in names]
    s.record(check_id, not missing, f"declared: {', '.join(sorted(n for n in names if n in wanted)) or 'none of them'}"
             + (f"; missing: {', '.join(missing)}" if missing else ""), f"{', '.join(wanted)} declared")
