"""Places the box of the Gazebo world: one SetEntityPose request to the world's set_pose service, then ends.

Gazebo's UserCommands system offers the service on its own transport; ros_gz_bridge makes it a ROS 2
service (send_poses_to_gazebo_launch.py starts the bridge beside this node).
"""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from ros_gz_interfaces.srv import SetEntityPose

WORLD = 'shapes_with_tf2_and_wrench'
SERVICE = f'/world/{WORLD}/set_pose'
ENTITY = 'box'  # set_pose finds an entity by its name (the Entity tree of Gazebo's GUI shows it)
POSITION = (0.0, 0.0, 50.0)  # metres, in the world frame: 50 m up, so it falls back onto the ground


class SendPosesToGazeboNode(Node):
    """A client of the world's set_pose service."""

    def __init__(self) -> None:
        super().__init__('send_poses_to_gazebo_node')
        self.client = self.create_client(SetEntityPose, SERVICE)

    def wait_for_world(self) -> None:
        """Wait until the service is there, saying so once a second.

        spin_once, not wait_for_service(): Jazzy's wait_for_service raises an RCLError when Ctrl+C shuts
        the context down while it waits; spin_once raises ExternalShutdownException, which main catches.
        """
        while not self.client.service_is_ready():
            self.get_logger().info(f'service {SERVICE} not available, waiting...')
            rclpy.spin_once(self, timeout_sec=1.0)

    def send_pose(self):
        """Ask for the box at POSITION, upright; returns the call's future."""
        request = SetEntityPose.Request()
        request.entity.name = ENTITY
        request.pose.position.x, request.pose.position.y, request.pose.position.z = POSITION
        request.pose.orientation.w = 1.0  # no rotation (x, y, z are 0)
        return self.client.call_async(request)


def main(args=None) -> None:
    """Send one pose, wait for the world's answer, log it and end."""
    try:
        rclpy.init(args=args)
        node = SendPosesToGazeboNode()
        node.wait_for_world()
        future = node.send_pose()
        rclpy.spin_until_future_complete(node, future)
        response = future.result()
        node.get_logger().info(f'set_pose of {ENTITY} to {POSITION}: '
                               f'{"success" if response is not None and response.success else "failed"}')
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
