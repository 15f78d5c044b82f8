"""A node with a subscriber: logs every AmazingQuote received on /amazing_quote (seed ch. 18.4)."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from package_with_interfaces.msg import AmazingQuote


class AmazingQuoteSubscriberNode(Node):
    """Logs the text, the philosopher and the id of each quote it receives."""

    def __init__(self) -> None:
        super().__init__('amazing_quote_subscriber_node')
        # Topic name, message type and QoS must match the publisher's.
        self.amazing_quote_subscriber = self.create_subscription(
            msg_type=AmazingQuote,
            topic='/amazing_quote',
            callback=self.amazing_quote_subscriber_callback,
            qos_profile=1)

    def amazing_quote_subscriber_callback(self, msg: AmazingQuote) -> None:
        """Called by the executor for every message that arrives."""
        self.get_logger().info(
            'I have received the most amazing of quotes.\n'
            f"    '{msg.quote}'\n"
            f'        -- {msg.philosopher_name}\n'
            f'This latest quote had the id={msg.id}.')


def main(args=None) -> None:
    """Spin the node until Ctrl+C (KeyboardInterrupt or, in Jazzy, ExternalShutdownException)."""
    try:
        rclpy.init(args=args)
        node = AmazingQuoteSubscriberNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
