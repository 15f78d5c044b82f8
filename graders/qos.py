"""Grader for ``qos`` (issue 20; contract in chapters/qos/CONTRACT.md).

Black-box, on the graph's own QoS information (what ``ros2 topic info --verbose``
prints, judged with ``rclpy.qos.qos_check_compatible``) and on what the
grader's probes of chosen profiles receive:

* **sensor**: a BEST_EFFORT probe (``qos_profile_sensor_data``) must receive the
  10 Hz stream; a RELIABLE probe must not match the sensor publisher; the offer is VOLATILE.
* **config**: the grader changes the ``units`` parameter, then a
  TRANSIENT_LOCAL probe made after that (a late joiner) must receive the
  current configuration, and only it (depth 1).
* **monitor**: the grader publishes its own latched configuration *before* the
  monitor starts, and its own BEST_EFFORT temperatures; the monitor must log both.
* **cli**: the learner's ``cli/qos_topic_info.sh`` runs against two grader nodes of
  random names and must print their QoS (``ros2 topic info --verbose``).

Each executable is a part of its own (partial credit), ending with its Ctrl+C check. Each part's
procedure is a function of the lesson's helper, graders/_qos.py, which imports rclpy and the message
packages inside its functions: a grader module is also loaded for its CHECKS alone (``ros2course list``,
``hint``), where ROS is not needed.
"""

from __future__ import annotations

from ros2course import kit
from ros2course.kit import Check, Session, checks

from . import _qos

PACKAGE = "python_package_that_uses_qos"
SENSOR_EXE = SENSOR_NODE = "sensor_publisher_node"
CONFIG_EXE = CONFIG_NODE = "config_publisher_node"
MONITOR_EXE = MONITOR_NODE = "sensor_monitor_node"
SENSOR_TOPIC = "/temperature"
SENSOR_TYPE = "sensor_msgs/msg/Temperature"
CONFIG_TOPIC = "/sensor_config"
CONFIG_TYPE = "std_msgs/msg/String"
FRAME_ID = "temperature_sensor"
PERIOD = 0.1  # seconds between readings (10 Hz)
#: Readings judged -> 19 intervals. At 10 Hz a machine running two checks at once delays one reading
#: by up to ~0.3 s now and then (seen in dev validate under a load of 10 on 2 cores); over 9 intervals
#: that alone moved a correct timer outside ±15 %, over 19 it stays inside.
SAMPLES = 20
#: The first reading is not judged: its timer's first tick comes while the process is still starting
#: (a late first stamp made the first interval 0.015 s in most runs).
WARM_UP = 1
START_TIMEOUT = 5.0  # seconds from the node appearing to its first reading
DEFAULT_UNITS = "celsius"
#: Temperatures of the grader's own the monitor must log (of the ones it published).
LOGGED_READINGS = 3
SCRIPT = "cli/qos_topic_info.sh"
SCRIPT_TIMEOUT = 25.0  # seconds; each `ros2` command takes ~1 s to start

#: Seconds of observation the contract needs: 21 readings at 10 Hz, the configuration change and the
#: late joiner's replay (one delivery each), 3 of the grader's readings logged by the monitor.
WINDOW = (WARM_UP + SAMPLES) * PERIOD + 2 * 0.5 + LOGGED_READINGS * PERIOD

SENSOR = {"part": "sensor", "needs": ("sensor_executable",)}
CONFIG = {"part": "config", "needs": ("config_executable",)}
MONITOR = {"part": "monitor", "needs": ("monitor_executable",)}
CLI = {"part": "cli", "needs": ("cli_script",)}
SENSOR_HINT = "create_publisher(Temperature, '/temperature', qos_profile_sensor_data) (from rclpy.qos)"
LATCHED_HINT = ("QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE, "
                "durability=DurabilityPolicy.TRANSIENT_LOCAL)")

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("depends", "package.xml depends on rclpy, std_msgs and sensor_msgs", 1,
          "add <depend>rclpy</depend>, <depend>std_msgs</depend> and <depend>sensor_msgs</depend> to package.xml"),
    *checks.started("sensor", PACKAGE, SENSOR_EXE, SENSOR_NODE, part="sensor"),
    Check("sensor_topic", f"It publishes {SENSOR_TOPIC} of type {SENSOR_TYPE}", 1, SENSOR_HINT, **SENSOR),
    Check("sensor_best_effort", "It offers BEST_EFFORT: a RELIABLE subscription never matches it", 2,
          "a reading lost is not worth resending: use qos_profile_sensor_data (BEST_EFFORT, VOLATILE, KEEP_LAST 5) "
          "instead of a plain depth", **SENSOR),
    Check("sensor_volatile", "It offers VOLATILE durability, as the sensor-data profile does", 1,
          "qos_profile_sensor_data is VOLATILE: a stale reading is never replayed to a subscription that joins later "
          "(TRANSIENT_LOCAL is for a latched configuration, not a stream)", **SENSOR),
    Check("sensor_stream", f"A BEST_EFFORT subscription receives the readings (frame_id {FRAME_ID!r})", 2,
          f"set msg.header.frame_id = '{FRAME_ID}' and msg.temperature, then publish", **SENSOR),
    Check("sensor_rate", "One reading every 0.1 s (10 Hz)", 2, "self.create_timer(0.1, self.timer_callback)",
          **SENSOR),
    checks.ctrl_c("sensor_sigint_exit", "the sensor publisher", **SENSOR),
    *checks.started("config", PACKAGE, CONFIG_EXE, CONFIG_NODE, part="config"),
    Check("config_topic", f"It publishes {CONFIG_TOPIC} of type {CONFIG_TYPE}", 1,
          f"create_publisher(String, '{CONFIG_TOPIC}', latched_qos)", **CONFIG),
    Check("config_initial", f"At start it publishes 'units: {DEFAULT_UNITS}' (the parameter's default), "
          "replayed to a later TRANSIENT_LOCAL subscription", 1,
          f"declare_parameter('units', '{DEFAULT_UNITS}'), create the latched publisher, then publish "
          f"String(data='units: {DEFAULT_UNITS}') once in __init__", **CONFIG),
    Check("config_start_parameter", "Started with units set (-p units:=kelvin), it publishes that value at start",
          1, "publish f\"units: {self.get_parameter('units').value}\" at start, not a fixed 'units: celsius'",
          **CONFIG),
    Check("config_republish", "Setting the parameter units publishes 'units: <new value>', and only then", 1,
          "declare_parameter('units', 'celsius'); add_post_set_parameters_callback(...) publishes the new "
          "configuration", **CONFIG),
    Check("config_late_joiner", "A TRANSIENT_LOCAL subscription made after the configuration was published "
          "still receives it", 3, "durability=DurabilityPolicy.TRANSIENT_LOCAL on the publisher: it keeps its "
          "last messages for subscriptions that join later", **CONFIG),
    Check("config_depth", "The late joiner receives only the current configuration (KEEP_LAST, depth 1)", 2,
          "history=HistoryPolicy.KEEP_LAST, depth=1: the publisher keeps (and replays) only its last message",
          part="config", needs=("config_republish", "config_late_joiner")),
    Check("config_latched", "It offers RELIABLE and TRANSIENT_LOCAL (ros2 topic info --verbose)", 2, LATCHED_HINT,
          **CONFIG),
    checks.ctrl_c("config_sigint_exit", "the configuration publisher", **CONFIG),
    *checks.started("monitor", PACKAGE, MONITOR_EXE, MONITOR_NODE, part="monitor"),
    Check("monitor_topics", f"It subscribes to {SENSOR_TOPIC} ({SENSOR_TYPE}) and {CONFIG_TOPIC} ({CONFIG_TYPE})",
          1, "two create_subscription calls in __init__", **MONITOR),
    Check("monitor_sensor_qos", f"Its {SENSOR_TOPIC} subscription matches a BEST_EFFORT publisher", 2,
          "a RELIABLE request never matches a BEST_EFFORT offer: subscribe with qos_profile_sensor_data",
          **MONITOR),
    Check("monitor_config_qos", f"Its {CONFIG_TOPIC} subscription asks for the latched profile: RELIABLE, "
          "TRANSIENT_LOCAL", 2, "a VOLATILE subscription gets nothing published before it started; the monitor "
          "subscribes with the same latched profile as the publisher: " + LATCHED_HINT, **MONITOR),
    Check("monitor_logs_config", "It logs the configuration published before it started ('Config: ...')", 2,
          "self.get_logger().info(f'Config: {msg.data}') in the configuration callback", **MONITOR),
    Check("monitor_logs_each_config", "It logs a configuration published while it runs, too", 1,
          "log in the configuration callback itself, for every message: no flag that stops after the first",
          part="monitor", needs=("monitor_executable", "monitor_logs_config")),
    Check("monitor_logs_sensor", "It logs the readings it receives ('Temperature: 21.50')", 2,
          "self.get_logger().info(f'Temperature: {msg.temperature:.2f}') in the temperature callback", **MONITOR),
    Check("monitor_logs_every_reading", "It logs every reading, not some of them", 1,
          "log in the temperature callback, each time, with no throttle_duration_sec", **MONITOR),
    checks.ctrl_c("monitor_sigint_exit", "the monitor", **MONITOR),
    Check("cli_script", f"{SCRIPT} exists and is valid bash", 1, part="cli"),
    Check("cli_ends", "The script ends by itself, with exit code 0", 1, **CLI),
    Check("cli_sensor_qos", f"It prints the QoS of {SENSOR_TOPIC}'s publisher (Reliability: BEST_EFFORT)", 2,
          f"ros2 topic info --verbose {SENSOR_TOPIC}", **CLI),
    Check("cli_config_qos", f"It prints the QoS of {CONFIG_TOPIC}'s publisher (Durability: TRANSIENT_LOCAL)", 2,
          f"ros2 topic info --verbose {CONFIG_TOPIC}", **CLI),
]


def grade(s: Session) -> None:
    """Grade the three nodes and the script, each a part of its own (see the module docstring)."""
    kit.depends(s, "depends", PACKAGE, ("rclpy", "std_msgs", "sensor_msgs"))
    temperature, string = _qos.message_types()
    with s.part("config"):  # first, in s.ros: the parameter client of the kit asks there
        _qos.grade_config(s, string, PACKAGE, CONFIG_EXE, CONFIG_NODE, topic=CONFIG_TOPIC, type_name=CONFIG_TYPE,
                          default_units=DEFAULT_UNITS)
    with s.part("sensor", own_graph=True):
        _qos.grade_sensor(s, temperature, PACKAGE, SENSOR_EXE, SENSOR_NODE, topic=SENSOR_TOPIC, type_name=SENSOR_TYPE,
                          frame_id=FRAME_ID, period=PERIOD, samples=SAMPLES, warm_up=WARM_UP,
                          start_timeout=START_TIMEOUT)
    with s.part("monitor", own_graph=True):
        _qos.grade_monitor(s, temperature, string, PACKAGE, MONITOR_EXE, MONITOR_NODE, sensor_topic=SENSOR_TOPIC,
                           sensor_type_name=SENSOR_TYPE, config_topic=CONFIG_TOPIC, config_type_name=CONFIG_TYPE,
                           period=PERIOD, logged=LOGGED_READINGS)
    with s.part("cli", own_graph=True):
        _qos.grade_cli(s, temperature, string, SCRIPT, timeout=SCRIPT_TIMEOUT, sensor_topic=SENSOR_TOPIC,
                       config_topic=CONFIG_TOPIC)
