"""Pushes the box of the Gazebo world once: one EntityWrench on the world's wrench topic."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from ros_gz_interfaces.msg import EntityWrench

WORLD = 'shapes_with_tf2_and_wrench'
TOPIC = f'/world/{WORLD}/wrench'
ENTITY_ID = 9  # the box's link: Gazebo finds a wrench's entity by its id
FORCE = (1000.0, 0.0, 0.0)  # newtons, in the world frame


class SendWrenchesToGazeboNode(Node):
    """A publisher of one wrench, once the world listens."""

    def __init__(self) -> None:
        super().__init__('send_wrenches_to_gazebo_node')
        self.publisher = self.create_publisher(EntityWrench, TOPIC, 1)

    def wait_for_world(self) -> None:
        """A message published before anyone subscribes is lost: wait for the world (the bridge)."""
        # TODO 9: while nothing subscribes to TOPIC, log that you wait and rclpy.spin_once(self, timeout_sec=1.0)
        pass

    def send_wrench(self) -> None:
        """Publish FORCE (no torque) for the box."""
        message = EntityWrench()
        # TODO 10: the entity id and the force; publish it and log what you sent


def main(args=None) -> None:
    """Send one wrench, then keep the node alive until Ctrl+C."""
    try:
        rclpy.init(args=args)
        node = SendWrenchesToGazeboNode()
        node.wait_for_world()
        node.send_wrench()
        # TODO 11: keep the node spinning until Ctrl+C
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
