"""The node of lesson hello-node: logs one line, then spins until Ctrl+C."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node


class HelloNodeNode(Node):
    def __init__(self):
        super().__init__("hello_node")
        self.get_logger().info("hello_node is up")


def main(args=None):
    try:
        rclpy.init(args=args)
        rclpy.spin(HelloNodeNode())
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
