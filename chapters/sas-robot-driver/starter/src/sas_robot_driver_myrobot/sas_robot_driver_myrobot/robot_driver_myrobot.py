"""The driver of myrobot: a subclass of sas's RobotDriver (seed ch. 31.5).

This example robot is simulated: a commanded target becomes the joint
positions at once.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from sas_robot_driver_myrobot.sas_lite import RobotDriver

#: myrobot has six joints.
JOINT_COUNT = 6


@dataclasses.dataclass
class RobotDriverMyrobotConfiguration:
    """What the driver needs to know: the robot's ``ip`` and ``(min, max)`` joint limits in radians."""

    ip: str
    joint_limits: tuple[np.ndarray, np.ndarray]


class RobotDriverMyrobot(RobotDriver):
    """myrobot's life cycle: connect, initialize, read/command, deinitialize, disconnect."""

    def __init__(self, configuration: RobotDriverMyrobotConfiguration) -> None:
        super().__init__()
        self.configuration = configuration
        self.joint_limits = configuration.joint_limits  # for the superclass
        self._connected = False
        self._motor_on = False
        # An empty vector means "no valid joint positions" (not connected).
        self._joint_positions = np.array([])

    def connect(self) -> None:
        # TODO: raise if already connected; mark connected, motors off, and six zero joint positions.
        pass

    def initialize(self) -> None:
        # TODO: raise if not connected; turn the motors on.
        pass

    def get_joint_positions(self) -> np.ndarray:
        # TODO: raise when the positions are not valid (empty); otherwise return a copy.
        return self._joint_positions

    def set_target_joint_positions(self, desired_joint_positions_rad: np.ndarray) -> None:
        # TODO: raise ValueError unless there are exactly JOINT_COUNT values; then they become the positions.
        pass

    def deinitialize(self) -> None:
        # TODO: motors off. Must never raise.
        pass

    def disconnect(self) -> None:
        # TODO: not connected any more, positions invalid again. Must never raise.
        pass
