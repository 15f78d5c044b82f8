"""Pushes the box of the Gazebo world once: one EntityWrench on the world's wrench topic.

Gazebo's ApplyLinkWrench system listens on /world/<world>/wrench and applies each wrench for one
simulation step; it finds the entity by its id (the name is not used there).
"""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from ros_gz_interfaces.msg import EntityWrench

WORLD = 'shapes_with_tf2_and_wrench'
TOPIC = f'/world/{WORLD}/wrench'
ENTITY_ID = 9  # the box's entity id in Gazebo (its GUI's Component Inspector shows it)
FORCE = (1000.0, 0.0, 0.0)  # newtons, in the world frame


class SendWrenchesToGazeboNode(Node):
    """A publisher of one wrench, once the world listens."""

    def __init__(self) -> None:
        super().__init__('send_wrenches_to_gazebo_node')
        self.publisher = self.create_publisher(EntityWrench, TOPIC, 1)

    def wait_for_world(self) -> None:
        """A message published before anyone subscribes is lost: wait for the world (the bridge)."""
        while self.publisher.get_subscription_count() == 0:
            self.get_logger().info(f'waiting for a subscriber on {TOPIC}...')
            rclpy.spin_once(self, timeout_sec=1.0)  # unlike time.sleep, Ctrl+C ends it cleanly

    def send_wrench(self) -> None:
        """Publish FORCE (no torque) for the box."""
        message = EntityWrench()
        message.entity.id = ENTITY_ID
        message.wrench.force.x, message.wrench.force.y, message.wrench.force.z = FORCE
        self.publisher.publish(message)
        self.get_logger().info(f'sent entity {ENTITY_ID} a force of {FORCE} N')


def main(args=None) -> None:
    """Send one wrench, then keep the node alive until Ctrl+C."""
    try:
        rclpy.init(args=args)
        node = SendWrenchesToGazeboNode()
        node.wait_for_world()
        node.send_wrench()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
