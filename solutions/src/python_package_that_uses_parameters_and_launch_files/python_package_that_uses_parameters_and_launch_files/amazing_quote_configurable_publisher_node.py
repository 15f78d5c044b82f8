"""An AmazingQuote publisher configured through ROS 2 parameters (seed ch. 22.3-22.6)."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from package_with_interfaces.msg import AmazingQuote


class AmazingQuoteConfigurablePublisherNode(Node):
    """Publishes an AmazingQuote on `topic_name` every `period` seconds.

    `topic_name` and `period` are read once, when the node starts; `quote` and
    `philosopher_name` are read on every publish, so changing them at runtime
    (`ros2 param set`, `ros2 param load`) changes the next messages.
    """

    def __init__(self) -> None:
        super().__init__('amazing_quote_configurable_publisher_node')

        # Read on every publish (see timer_callback).
        self.declare_parameter('quote', 'Use the force, Pikachu!')
        self.declare_parameter('philosopher_name', 'Uncle Ben')

        # Read once: the publisher and the timer are created with them.
        self.declare_parameter('topic_name', 'amazing_quote')
        topic_name: str = self.get_parameter('topic_name').get_parameter_value().string_value
        self.declare_parameter('period', 0.5)
        timer_period: float = self.get_parameter('period').get_parameter_value().double_value

        self.configurable_amazing_quote_publisher = self.create_publisher(
            msg_type=AmazingQuote,
            topic=topic_name,
            qos_profile=1)
        self.timer = self.create_timer(timer_period, self.timer_callback)
        self.incremental_id: int = 0

    def timer_callback(self) -> None:
        """Publish one quote with the parameters' current values."""
        amazing_quote = AmazingQuote()
        amazing_quote.id = self.incremental_id
        amazing_quote.quote = self.get_parameter('quote').get_parameter_value().string_value
        amazing_quote.philosopher_name = self.get_parameter('philosopher_name').get_parameter_value().string_value
        self.configurable_amazing_quote_publisher.publish(amazing_quote)
        self.incremental_id += 1


def main(args=None) -> None:
    """Spin the node until Ctrl+C (KeyboardInterrupt or, in Jazzy, ExternalShutdownException)."""
    try:
        rclpy.init(args=args)
        node = AmazingQuoteConfigurablePublisherNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
