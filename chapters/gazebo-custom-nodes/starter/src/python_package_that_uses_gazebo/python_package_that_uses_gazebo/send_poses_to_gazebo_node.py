"""Places the box of the Gazebo world: one SetEntityPose request to the world's set_pose service, then ends."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from ros_gz_interfaces.srv import SetEntityPose

WORLD = 'shapes_with_tf2_and_wrench'
SERVICE = f'/world/{WORLD}/set_pose'
ENTITY = 'box'
POSITION = (0.0, 0.0, 50.0)  # metres, in the world frame


class SendPosesToGazeboNode(Node):
    """A client of the world's set_pose service."""

    def __init__(self) -> None:
        super().__init__('send_poses_to_gazebo_node')
        # TODO 4: a client of SetEntityPose on SERVICE

    def wait_for_world(self) -> None:
        """Wait until the service is there, saying so once a second."""
        # TODO 5: while the service is not ready (service_is_ready()): log it, then rclpy.spin_once(self,
        #         timeout_sec=1.0) (not wait_for_service(): in Jazzy it raises an error on Ctrl+C)

    def send_pose(self):
        """Ask for the box at POSITION, upright; returns the call's future."""
        request = SetEntityPose.Request()
        # TODO 6: the entity's name, the position and the orientation (no rotation: w = 1.0)
        return None  # TODO 7: call the service asynchronously and return its future


def main(args=None) -> None:
    """Send one pose, wait for the world's answer, log it and end."""
    try:
        rclpy.init(args=args)
        node = SendPosesToGazeboNode()
        node.wait_for_world()
        future = node.send_pose()
        # TODO 8: spin until the future is complete, then log the answer (response.success)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
