"""The ROS side of a driver: what ``sas::RobotDriverROS`` gives a C++ driver for free.

Every topic starts with the prefix (the node's name), so several robots can
run side by side (``myrobot_1``, ``myrobot_2``...):

* publishes ``<prefix>/get/joint_states`` (``sensor_msgs/JointState``, radians)
  and ``<prefix>/get/joint_positions_min`` / ``_max`` (``std_msgs/Float64MultiArray``)
  every ``thread_sampling_time_sec``;
* subscribes ``<prefix>/set/target_joint_positions`` (``std_msgs/Float64MultiArray``)
  and applies the latest target in every loop, once one was received.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from rclpy.executors import SingleThreadedExecutor
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from sas_robot_driver_myrobot.sas_lite import SAS_QOS_DEPTH, RobotDriver


@dataclasses.dataclass
class RobotDriverROSConfiguration:
    """``sas::RobotDriverROSConfiguration``.

    Attributes:
        thread_sampling_time_sec: period of the control loop, seconds (0.002 = 500 Hz).
        robot_driver_provider_prefix: the topic prefix, normally the node's name.
    """

    thread_sampling_time_sec: float
    robot_driver_provider_prefix: str


class RobotDriverROS:
    """Runs a :class:`RobotDriver` and exposes it with the sas topics."""

    def __init__(self, node, robot_driver: RobotDriver, configuration: RobotDriverROSConfiguration) -> None:
        self._node = node
        self._driver = robot_driver
        self._configuration = configuration
        prefix = configuration.robot_driver_provider_prefix
        self._joint_states_publisher = node.create_publisher(
            JointState, f'{prefix}/get/joint_states', SAS_QOS_DEPTH)
        self._min_publisher = node.create_publisher(
            Float64MultiArray, f'{prefix}/get/joint_positions_min', SAS_QOS_DEPTH)
        self._max_publisher = node.create_publisher(
            Float64MultiArray, f'{prefix}/get/joint_positions_max', SAS_QOS_DEPTH)
        self._target_subscriber = node.create_subscription(
            Float64MultiArray, f'{prefix}/set/target_joint_positions', self._on_target, SAS_QOS_DEPTH)
        self._target: np.ndarray | None = None
        limits_min, limits_max = robot_driver.get_joint_limits()
        self._min_msg = Float64MultiArray(data=[float(x) for x in limits_min])
        self._max_msg = Float64MultiArray(data=[float(x) for x in limits_max])
        self._timer = None

    def _on_target(self, msg: Float64MultiArray) -> None:
        self._target = np.array(msg.data)

    def _loop_once(self) -> None:
        """One control loop iteration: apply the target, read, publish."""
        if self._target is not None:
            try:
                self._driver.set_target_joint_positions(self._target)
            except ValueError as e:
                self._node.get_logger().error(f'::Target not applied: {e}')
                self._target = None  # keep streaming the previous positions
        msg = JointState()
        msg.header.stamp = self._node.get_clock().now().to_msg()
        msg.position = [float(x) for x in self._driver.get_joint_positions()]
        self._joint_states_publisher.publish(msg)
        self._min_publisher.publish(self._min_msg)
        self._max_publisher.publish(self._max_msg)

    def control_loop(self) -> None:
        """Connect, initialize, then run the loop every ``thread_sampling_time_sec`` until shutdown."""
        self._node.get_logger().info('::Connecting...')
        self._driver.connect()
        self._node.get_logger().info('::Initializing...')
        self._driver.initialize()
        self._node.get_logger().info('::Running the control loop.')
        self._timer = self._node.create_timer(self._configuration.thread_sampling_time_sec, self._loop_once)
        executor = SingleThreadedExecutor()
        executor.add_node(self._node)
        executor.spin()
