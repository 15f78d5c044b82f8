"""Grader for ``gazebo-custom-nodes`` (GitHub issue 40; contract in chapters/gazebo-custom-nodes/CONTRACT.md).

Three nodes of ``python_package_that_uses_gazebo`` that move the box of the author's Gazebo world, which
never runs here: the grader's world (MuJoCo, :mod:`ros2course.kit.world`) serves the same box, service and
topics (graders/_gazebo.py), each run in a graph of its own.

* **pose**: ``send_poses_to_gazebo_node`` with no world at first (it must say it waits, at most once a
  second); then the world's
  ``set_pose`` appears: one request, the box at (0, 0, 50), upright; the node ends by itself.
* **wrench**: ``send_wrenches_to_gazebo_node`` with nothing subscribed to the wrench topic at first (it must
  say it waits, at most once a second); then the world subscribes: one message, entity 9, 1000 N along x;
  the node keeps spinning.
* **thrust**: ``control_shape_thrust_node`` on the world's clock, in lockstep, from the box at rest at x = 0:
  a force every step, each -5 (x + 3) N for the box's latest transform, and the box at rest where that law
  brings it.
* **files**: the three launch files and the bridge file, read without running them.
* Ctrl+C while the pose client waits for the world, and ends the two nodes that spin.
"""

from __future__ import annotations

from ros2course import kit
from ros2course.kit import Check, Session, checks
from ros2course.kit.settle import part_needed

from . import _gazebo as steps
from ._gazebo import (
    BRIDGE_FILE,
    ENTITY_ID,
    GAIN,
    PACKAGE,
    POSE_EXECUTABLE,
    POSE_NODE,
    SET_POSE,
    TARGET_X,
    THRUST_EXECUTABLE,
    THRUST_NODE,
    WRENCH_EXECUTABLE,
    WRENCH_NODE,
    WRENCH_TOPIC,
)

#: Seconds the contract needs the nodes watched (benchmarks/all_lessons.py): each waiting node's first record and
#: 2.5 s more of waiting records, the 2 s after the push, and the thrust run's 4 s of sim time (about 2 s of wall time in lockstep).
WINDOW = 2 * (3.0 + 2.5) + 2.0 + 4.0

POSE = {"needs": ("pose_executable",), "part": "pose"}
WRENCH = {"needs": ("wrench_sent",), "part": "wrench"}
THRUST = {"needs": ("thrust_node_name",), "part": "thrust"}
CHECKS = [
    Check("build", "The package builds with colcon", 1,
          f"colcon build --packages-up-to {PACKAGE} and read its first error (often a typo in setup.py's "
          "console_scripts or data_files, or in package.xml)"),
    Check("depends", "package.xml depends on rclpy, ros_gz_interfaces and tf2_ros", 1,
          "add <depend>ros_gz_interfaces</depend> and <depend>tf2_ros</depend> next to rclpy in package.xml"),
    Check("launch_files", "The three launch files are installed, each with its node and a ros_gz_bridge", 2,
          "put send_poses_to_gazebo_launch.py, send_wrenches_to_gazebo_launch.py and control_shape_thrust_launch.py "
          "in launch/ and install them (data_files: ('share/' + package_name + '/launch', glob('launch/*_launch.py'))); "
          "each starts its node (package='python_package_that_uses_gazebo', under its own name: no other name=) and "
          "Node(package='ros_gz_bridge', executable='parameter_bridge', ...), one bridge per "
          "argument string (arguments=['<topic>@<ROS type>]<Gazebo type>'], nothing else in it); the thrust one "
          "gives the node parameters=[{'use_sim_time': True}] and the bridge its config_file"),
    Check("bridge_config", f"config_bridge/{BRIDGE_FILE} bridges /clock, the box's pose and the wrench topic", 1,
          "three entries (ros_topic_name, gz_topic_name, ros_type_name, gz_type_name, direction): /clock and /tf "
          "(from /model/box/pose, gz.msgs.Pose_V) GZ_TO_ROS, the wrench topic ROS_TO_GZ; install the file "
          "(data_files: ('share/' + package_name + '/config_bridge', glob('config_bridge/*.yaml')))"),
    *checks.started("pose", PACKAGE, POSE_EXECUTABLE, POSE_NODE, part="pose"),
    Check("pose_waits", f"While {SET_POSE} is missing, it says in its log that it waits", 1,
          "while not self.client.service_is_ready(): self.get_logger().info('service ... not available, "
          "waiting...'); rclpy.spin_once(self, timeout_sec=1.0)", **POSE),
    Check("pose_waits_throttled", "It says so at most once a second", 1,
          "wait a second between two looks: rclpy.spin_once(self, timeout_sec=1.0) in the loop (with a shorter "
          "timeout the log fills with waiting records)", needs=("pose_waits",), part="pose"),
    Check("pose_request", "It asks once for the box at (0, 0, 50), upright", 2,
          "request = SetEntityPose.Request(); request.entity.name = 'box'; request.pose.position.z = 50.0; "
          "request.pose.orientation.w = 1.0; self.client.call_async(request), once", **POSE),
    Check("pose_ends", "Once the world has answered, the node ends by itself: exit code 0, no traceback", 1,
          "rclpy.spin_until_future_complete(node, future) in main, then return (no rclpy.spin afterwards)",
          needs=("pose_request",), part="pose"),
    checks.ctrl_c("pose_sigint_exit", "the pose client while it waits for the world", needs=("pose_executable",),
                  part="pose_interrupted"),
    *checks.started("wrench", PACKAGE, WRENCH_EXECUTABLE, WRENCH_NODE, part="wrench"),
    Check("wrench_waits", f"While nothing subscribes to {WRENCH_TOPIC}, it waits, saying so in its log once a "
          "second", 1,
          "while self.publisher.get_subscription_count() == 0: log '... waiting ...' and "
          "rclpy.spin_once(self, timeout_sec=1.0)",
          needs=("wrench_executable",), part="wrench"),
    Check("wrench_waits_throttled", "It says so at most once a second", 1,
          "wait a second between two looks: rclpy.spin_once(self, timeout_sec=1.0) in the loop",
          needs=("wrench_waits",), part="wrench"),
    Check("wrench_sent", "Once the world subscribes, it publishes an EntityWrench", 1,
          f"publish after the wait (a message published before anyone subscribes is lost); "
          f"self.create_publisher(EntityWrench, '{WRENCH_TOPIC}', 1)", needs=("wrench_executable",), part="wrench"),
    Check("wrench_once", "It publishes the wrench once", 1, "publish once, then rclpy.spin(node)", **WRENCH),
    Check("wrench_values", f"The wrench: entity id {ENTITY_ID}, 1000 N along x, no torque", 2,
          f"message.entity.id = {ENTITY_ID} (Gazebo finds the entity by its id; a name alone is ignored); "
          "message.wrench.force.x = 1000.0; leave torque at 0", **WRENCH),
    Check("wrench_logged", "It logs what it sent (the force)", 1,
          "after publishing: self.get_logger().info(f'sent entity {ENTITY_ID} a force of {FORCE} N')", **WRENCH),
    Check("wrench_spins", "After sending, the node keeps spinning until Ctrl+C", 1,
          "call rclpy.spin(node) after send_wrench(), so the node stays until Ctrl+C", **WRENCH),
    checks.ctrl_c("wrench_sigint_exit", "the wrench publisher", needs=("wrench_executable",), part="wrench"),
    *checks.started("thrust", PACKAGE, THRUST_EXECUTABLE, THRUST_NODE, part="thrust"),
    Check("thrust_waits", f"Before it starts, while nothing subscribes to {WRENCH_TOPIC}, it waits, saying so in "
          "its log once a second", 1, "as send_wrenches_to_gazebo_node does, in __init__ before the timer: while "
          "self.publisher.get_subscription_count() == 0: log, then rclpy.spin_once(self, timeout_sec=1.0)",
          needs=("thrust_executable",), part="thrust"),
    Check("thrust_waits_throttled", "It says so at most once a second", 1,
          "wait a second between two looks: rclpy.spin_once(self, timeout_sec=1.0) in the loop (without it the "
          "loop looks, and logs, as fast as it can)", needs=("thrust_waits",), part="thrust"),
    Check("thrust_no_transform", "While the world's clock runs and the box's transform is not there yet, it keeps "
          "running, publishes nothing and warns once a second (throttled)", 1,
          "try: lookup_transform(...) except tf2_ros.TransformException as exc: self.get_logger().warn(..., "
          "throttle_duration_sec=1.0); return", **THRUST),
    Check("thrust_entity", f"Each force is for entity {ENTITY_ID}, along x only", 1,
          f"message.entity.id = {ENTITY_ID}; only message.wrench.force.x set", **THRUST),
    Check("thrust_rate", "It answers every step of the world (a 1 kHz timer on the world's clock)", 2,
          "self.create_timer(0.001, self.timer_callback): with use_sim_time it ticks once per 0.004 s step of the "
          "world; publish one wrench per tick", **THRUST),
    Check("thrust_law", f"Each force is -{GAIN:g} * (x - ({TARGET_X:g})) N for the box's latest x", 3,
          "in the timer: transform = self.buffer.lookup_transform('shapes_with_tf2_and_wrench', 'box', Time()); "
          f"force.x = -{GAIN:g} * (transform.transform.translation.x - ({TARGET_X:g}))", **THRUST),
    Check("thrust_settles", "In closed loop, the box comes to rest where that law brings it", 2,
          "the box stops short of -3 m: friction holds it once the force is below mu m g = 9.8 N; a different "
          "gain, target or sign stops it elsewhere", **THRUST),
    checks.ctrl_c("thrust_sigint_exit", "the thrust controller", needs=("thrust_executable",), part="thrust"),
]


def grade(s: Session) -> None:
    """The files, then the pose client's two runs, the wrench publisher's and the thrust controller's."""
    kit.depends(s, "depends", PACKAGE, ("rclpy", "ros_gz_interfaces", "tf2_ros"))
    steps.launch_files(s)
    steps.bridge_config(s)
    # each part runs only if a check of it can still change the verdict (always, but in dev validate
    # --until-settled); pose_sigint_exit needs pose_executable, so the pose part runs whenever it does
    if part_needed(s, CHECKS, "pose"):
        with s.part("pose", own_graph=True):
            pose_path = kit.executable(s, "pose_executable", PACKAGE, POSE_EXECUTABLE)
            steps.pose_run(s, pose_path)
    if part_needed(s, CHECKS, "pose_interrupted"):
        with s.part("pose_interrupted", own_graph=True):
            s.require("pose_executable")
            steps.interrupted_run(s, "pose_sigint_exit", pose_path, POSE_NODE, f"{POSE_EXECUTABLE}.interrupted")
    if part_needed(s, CHECKS, "wrench"):
        with s.part("wrench", own_graph=True):
            steps.wrench_run(s, kit.executable(s, "wrench_executable", PACKAGE, WRENCH_EXECUTABLE))
    if part_needed(s, CHECKS, "thrust"):
        with s.part("thrust", own_graph=True):
            steps.thrust_run(s, kit.executable(s, "thrust_executable", PACKAGE, THRUST_EXECUTABLE))
