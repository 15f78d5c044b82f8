"""Small Python stand-ins for the SmartArmStack pieces the seed uses (ch. 31).

The real ``sas`` packages are C++ (with Python bindings) and cannot be
installed everywhere. This module gives the same *shapes*, so the rest of the
package reads like the seed:

* :class:`RobotDriver`: the abstract base class a driver subclasses
  (``sas::RobotDriver``): connect, initialize, read, command, deinitialize,
  disconnect.
* :class:`RobotDriverClient`: what a program uses to talk to a running driver
  (``sas_robot_driver.RobotDriverClient``): it subscribes to ``<prefix>/get/...``
  and publishes on ``<prefix>/set/target_joint_positions``.
* :class:`Clock`: a fixed-period loop timer (``sas_core.Clock``).

You do not need to change this file.
"""

from __future__ import annotations

import enum
import time
from abc import ABC, abstractmethod

import numpy as np
from rclpy.executors import ExternalShutdownException
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

#: sas creates all its publishers and subscribers with a history depth of 1.
SAS_QOS_DEPTH = 1


class RobotDriver(ABC):
    """The life cycle every sas driver implements (``sas::RobotDriver``).

    ``joint_limits`` is a ``(min, max)`` pair of arrays in radians, set by the subclass.
    """

    def __init__(self) -> None:
        self.joint_limits: tuple[np.ndarray, np.ndarray] = (np.array([]), np.array([]))

    def get_joint_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """The ``(min, max)`` joint limits in radians."""
        return self.joint_limits

    @abstractmethod
    def connect(self) -> None:
        """Connect to the robot. Must raise if the connection cannot be made."""

    @abstractmethod
    def initialize(self) -> None:
        """Turn the robot on. Must raise if that fails. Afterwards targets can be received."""

    @abstractmethod
    def get_joint_positions(self) -> np.ndarray:
        """Joint positions in radians. Must raise when they are not valid (e.g. not connected)."""

    @abstractmethod
    def set_target_joint_positions(self, desired_joint_positions_rad: np.ndarray) -> None:
        """Command joint positions in radians. Must raise on a vector of the wrong size."""

    @abstractmethod
    def deinitialize(self) -> None:
        """Turn the robot off. Must never raise (it runs while shutting down)."""

    @abstractmethod
    def disconnect(self) -> None:
        """Disconnect from the robot. Must never raise (it runs while shutting down)."""


class RobotDriverClient:
    """Talk to a running driver whose topics start with ``topic_prefix`` (e.g. ``myrobot_1``).

    Args:
        node: an rclpy node; spin it (e.g. ``rclpy.spin_once(node)``) so messages arrive.
        topic_prefix: the driver's node name.
    """

    def __init__(self, node, topic_prefix: str) -> None:
        self._node = node
        self._prefix = topic_prefix
        self._joint_positions: np.ndarray | None = None
        self._joint_positions_min: np.ndarray | None = None
        self._joint_positions_max: np.ndarray | None = None
        node.get_logger().info(f'::Initializing RobotDriverClient with prefix {topic_prefix}')
        self._subscribers = [
            node.create_subscription(JointState, f'{topic_prefix}/get/joint_states',
                                     self._on_joint_states, SAS_QOS_DEPTH),
            node.create_subscription(Float64MultiArray, f'{topic_prefix}/get/joint_positions_min',
                                     self._on_min, SAS_QOS_DEPTH),
            node.create_subscription(Float64MultiArray, f'{topic_prefix}/get/joint_positions_max',
                                     self._on_max, SAS_QOS_DEPTH),
        ]
        self._target_publisher = node.create_publisher(
            Float64MultiArray, f'{topic_prefix}/set/target_joint_positions', SAS_QOS_DEPTH)

    def _on_joint_states(self, msg: JointState) -> None:
        self._joint_positions = np.array(msg.position)

    def _on_min(self, msg: Float64MultiArray) -> None:
        self._joint_positions_min = np.array(msg.data)

    def _on_max(self, msg: Float64MultiArray) -> None:
        self._joint_positions_max = np.array(msg.data)

    def is_enabled(self) -> bool:
        """True once joint positions and both joint limits were received from the driver."""
        return (self._joint_positions is not None and self._joint_positions_min is not None
                and self._joint_positions_max is not None)

    def get_topic_prefix(self) -> str:
        """The driver's topic prefix (its node name)."""
        return self._prefix

    def get_joint_positions(self) -> np.ndarray | None:
        """The latest joint positions in radians (None before the first message)."""
        return None if self._joint_positions is None else self._joint_positions.copy()

    def get_joint_limits(self) -> tuple[np.ndarray | None, np.ndarray | None]:
        """The latest ``(min, max)`` joint limits in radians."""
        return self._joint_positions_min, self._joint_positions_max

    def send_target_joint_positions(self, target_joint_positions_rad) -> None:
        """Publish target joint positions (radians) on ``<prefix>/set/target_joint_positions``.

        Raises:
            ExternalShutdownException: ROS was shut down (Ctrl+C) before or while publishing, the
                way ``rclpy.spin()`` reports it in Jazzy: catch it to end your loop cleanly.
        """
        msg = Float64MultiArray()
        msg.data = [float(x) for x in target_joint_positions_rad]
        try:
            self._target_publisher.publish(msg)
        except Exception:
            # rclpy shuts the context down from its own thread on Ctrl+C; publishing then fails
            # with "publisher's context is invalid". Report that as the shutdown it is.
            if self._node.context.ok():
                raise
            raise ExternalShutdownException() from None


class Statistics(enum.Enum):
    """Which statistic :meth:`Clock.get_statistics` computes."""

    Mean = 'mean'
    Median = 'median'
    Max = 'max'
    Min = 'min'


class Clock:
    """Run a loop with a fixed period (seconds), like ``sas_core.Clock``.

    ``init()`` once, then ``update_and_sleep()`` once per iteration: it sleeps
    until the next multiple of the period since ``init()``.
    """

    class TimeType(enum.Enum):
        Computational = 'computational'
        Idle = 'idle'
        EffectiveSampling = 'effective sampling'

    def __init__(self, period: float) -> None:
        self.period = period
        self._next = 0.0
        self._last = 0.0
        self._times: dict[Clock.TimeType, list[float]] = {t: [] for t in Clock.TimeType}

    def init(self) -> None:
        """Start counting periods from now."""
        self._last = time.monotonic()
        self._next = self._last + self.period

    def update_and_sleep(self) -> None:
        """Sleep until the end of the current period (no sleep when the loop is late)."""
        now = time.monotonic()
        self._times[Clock.TimeType.Computational].append(now - self._last)
        idle = self._next - now
        if idle > 0.0:
            time.sleep(idle)
        self._times[Clock.TimeType.Idle].append(max(idle, 0.0))
        now = time.monotonic()
        self._times[Clock.TimeType.EffectiveSampling].append(now - self._last)
        self._last = now
        self._next = max(self._next + self.period, now)

    def get_statistics(self, statistics: Statistics, time_type: Clock.TimeType) -> float:
        """A statistic (seconds) of the recorded times of one type."""
        values = self._times[time_type]
        if not values:
            return 0.0
        functions = {Statistics.Mean: np.mean, Statistics.Median: np.median, Statistics.Max: np.max,
                     Statistics.Min: np.min}
        return float(functions[statistics](values))
