"""A node with a subscriber: logs every AmazingQuote received on /amazing_quote."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

# TODO 7: import the AmazingQuote message generated from package_with_interfaces


class AmazingQuoteSubscriberNode(Node):
    """Logs the text, the philosopher and the id of each quote it receives."""

    def __init__(self) -> None:
        # TODO 8: the node's name is amazing_quote_subscriber_node
        super().__init__('TODO')
        # TODO 9: a subscription to /amazing_quote (AmazingQuote, QoS depth 1) that calls
        #         self.amazing_quote_subscriber_callback for every message

    def amazing_quote_subscriber_callback(self, msg) -> None:
        """Called by the executor for every message that arrives."""
        # TODO 10: log msg.quote, msg.philosopher_name and msg.id with the node's logger


def main(args=None) -> None:
    """Spin the node until Ctrl+C."""
    try:
        rclpy.init(args=args)
        node = AmazingQuoteSubscriberNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
