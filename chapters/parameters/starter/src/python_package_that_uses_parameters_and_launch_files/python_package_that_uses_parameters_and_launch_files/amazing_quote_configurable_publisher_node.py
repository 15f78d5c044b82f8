"""An AmazingQuote publisher configured through ROS 2 parameters (lesson: parameters).

Right now everything is hard-coded. Make it configurable with four parameters:
quote, philosopher_name, topic_name and period (see the TODOs).
"""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from package_with_interfaces.msg import AmazingQuote


class AmazingQuoteConfigurablePublisherNode(Node):
    """Publishes an AmazingQuote on `topic_name` every `period` seconds."""

    def __init__(self) -> None:
        super().__init__('amazing_quote_configurable_publisher_node')

        # TODO: declare 'quote' (default 'Use the force, Pikachu!') and
        #       'philosopher_name' (default 'Uncle Ben'): they are read on every publish.

        # TODO: declare 'topic_name' (default 'amazing_quote') and 'period' (default 0.5),
        #       then read them here instead of these hard-coded values.
        topic_name: str = 'amazing_quote'
        timer_period: float = 0.5

        self.configurable_amazing_quote_publisher = self.create_publisher(
            msg_type=AmazingQuote,
            topic=topic_name,
            qos_profile=1)
        self.timer = self.create_timer(timer_period, self.timer_callback)
        self.incremental_id: int = 0

    def timer_callback(self) -> None:
        """Publish one quote."""
        amazing_quote = AmazingQuote()
        amazing_quote.id = self.incremental_id
        # TODO: use the current values of the 'quote' and 'philosopher_name' parameters.
        amazing_quote.quote = 'Use the force, Pikachu!'
        amazing_quote.philosopher_name = 'Uncle Ben'
        self.configurable_amazing_quote_publisher.publish(amazing_quote)
        self.incremental_id += 1


def main(args=None) -> None:
    """Spin the node until Ctrl+C."""
    try:
        rclpy.init(args=args)
        node = AmazingQuoteConfigurablePublisherNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
