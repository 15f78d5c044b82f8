"""A node with a publisher: an AmazingQuote on /amazing_quote twice a second (seed ch. 18.3)."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from package_with_interfaces.msg import AmazingQuote


class AmazingQuotePublisherNode(Node):
    """Publishes the same quote every 0.5 s, with an id counting up from 0."""

    def __init__(self) -> None:
        super().__init__('amazing_quote_publisher_node')
        # A QoS depth of 1 is enough: every message supersedes the previous one.
        self.amazing_quote_publisher = self.create_publisher(
            msg_type=AmazingQuote,
            topic='/amazing_quote',
            qos_profile=1)
        self.incremental_id: int = 0
        timer_period: float = 0.5  # seconds
        self.timer = self.create_timer(timer_period, self.timer_callback)

    def timer_callback(self) -> None:
        """Build one AmazingQuote, publish it, count up."""
        amazing_quote = AmazingQuote()
        amazing_quote.id = self.incremental_id
        amazing_quote.quote = 'Use the force, Pikachu!'
        amazing_quote.philosopher_name = 'Uncle Ben'
        self.amazing_quote_publisher.publish(amazing_quote)
        self.incremental_id += 1


def main(args=None) -> None:
    """Spin the node until Ctrl+C (KeyboardInterrupt or, in Jazzy, ExternalShutdownException)."""
    try:
        rclpy.init(args=args)
        node = AmazingQuotePublisherNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
