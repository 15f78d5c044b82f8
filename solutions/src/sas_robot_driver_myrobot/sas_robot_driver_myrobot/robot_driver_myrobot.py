"""The driver of myrobot: a subclass of sas's RobotDriver (seed ch. 31.5).

A real driver would talk to the robot at ``configuration.ip``. This example
robot is simulated, as in the seed: a commanded target becomes the joint
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
    """What the driver needs to know (``RobotDriverMyrobotConfiguration`` in the seed).

    Attributes:
        ip: the robot's address.
        joint_limits: ``(min, max)`` arrays in radians.
    """

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
        """Connect; raises if already connected. After connecting the positions are zeros."""
        if self._connected:
            raise RuntimeError('Already connected.')
        self._connected = True
        self._motor_on = False
        self._joint_positions = np.zeros(JOINT_COUNT)

    def initialize(self) -> None:
        """Turn the motors on; raises when not connected."""
        if not self._connected:
            raise RuntimeError('Tried to initialize a driver that is not connected.')
        self._motor_on = True

    def get_joint_positions(self) -> np.ndarray:
        """The joint positions in radians; raises when they are not valid."""
        if self._joint_positions.size == 0:
            raise RuntimeError('Tried to obtain invalid joint positions')
        return self._joint_positions.copy()

    def set_target_joint_positions(self, desired_joint_positions_rad: np.ndarray) -> None:
        """Take the target (radians) as the new joint positions; raises on a size other than 6."""
        desired = np.asarray(desired_joint_positions_rad, dtype=float)
        if desired.size != JOINT_COUNT:
            raise ValueError(f'Incorrect vector size in RobotDriverMyrobot.set_target_joint_positions: '
                             f'got {desired.size} values, expected {JOINT_COUNT}')
        self._joint_positions = desired.copy()

    def deinitialize(self) -> None:
        """Turn the motors off. Never raises."""
        self._motor_on = False

    def disconnect(self) -> None:
        """Disconnect. Never raises."""
        self._connected = False
        self._joint_positions = np.array([])
