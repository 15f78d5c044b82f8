"""The ROS side of a driver: what ``sas::RobotDriverROS`` gives a C++ driver for free.

Every topic starts with the prefix (the node's name):

* publishes ``<prefix>/get/joint_states`` (``sensor_msgs/JointState``, radians)
  and ``<prefix>/get/joint_positions_min`` / ``_max`` (``std_msgs/Float64MultiArray``)
  every ``thread_sampling_time_sec``;
* subscribes ``<prefix>/set/target_joint_positions`` (``std_msgs/Float64MultiArray``)
  and applies the latest target in every loop, once one was received.

All with a history depth of ``SAS_QOS_DEPTH`` (1).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from rclpy.executors import SingleThreadedExecutor
from sensor_msgs.msg import JointState  # noqa: F401
from std_msgs.msg import Float64MultiArray  # noqa: F401

from sas_robot_driver_myrobot.sas_lite import SAS_QOS_DEPTH, RobotDriver  # noqa: F401


@dataclasses.dataclass
class RobotDriverROSConfiguration:
    """``thread_sampling_time_sec``: loop period in seconds; ``robot_driver_provider_prefix``: the topic prefix."""

    thread_sampling_time_sec: float
    robot_driver_provider_prefix: str


class RobotDriverROS:
    """Runs a :class:`RobotDriver` and exposes it with the sas topics."""

    def __init__(self, node, robot_driver: RobotDriver, configuration: RobotDriverROSConfiguration) -> None:
        self._node = node
        self._driver = robot_driver
        self._configuration = configuration
        self._target: np.ndarray | None = None
        # TODO: the three publishers and the subscriber, named f'{prefix}/get/...' and f'{prefix}/set/...'

    def _on_target(self, msg) -> None:
        # TODO: keep the latest target; the loop applies it.
        pass

    def _loop_once(self) -> None:
        # TODO: apply the latest target (if any; a wrong-size target raises: log an error and keep the
        #       previous positions), then publish the joint states (with a stamp) and both limits.
        pass

    def control_loop(self) -> None:
        """Connect, initialize, then run the loop every ``thread_sampling_time_sec`` until shutdown."""
        self._driver.connect()
        self._driver.initialize()
        # TODO: a timer that calls self._loop_once every thread_sampling_time_sec
        executor = SingleThreadedExecutor()
        executor.add_node(self._node)
        executor.spin()
