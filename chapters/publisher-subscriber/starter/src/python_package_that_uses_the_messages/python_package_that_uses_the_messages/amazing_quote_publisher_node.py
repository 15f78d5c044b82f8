"""A node with a publisher: an AmazingQuote on /amazing_quote twice a second."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

# TODO 3: import the AmazingQuote message generated from package_with_interfaces


class AmazingQuotePublisherNode(Node):
    """Publishes the same quote every 0.5 s, with an id counting up from 0."""

    def __init__(self) -> None:
        # TODO 4: the node's name is amazing_quote_publisher_node
        super().__init__('TODO')
        # TODO 5: a publisher of AmazingQuote on /amazing_quote (QoS depth 1),
        #         an id counter starting at 0, and a timer calling timer_callback every 0.5 s

    def timer_callback(self) -> None:
        """Build one AmazingQuote, publish it, count up."""
        # TODO 6: fill id, quote ('Use the force, Pikachu!') and philosopher_name ('Uncle Ben'),
        #         publish the message, then add 1 to the counter


def main(args=None) -> None:
    """Spin the node until Ctrl+C."""
    try:
        rclpy.init(args=args)
        node = AmazingQuotePublisherNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
