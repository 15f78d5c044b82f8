"""A node that logs how many times it has logged, twice a second."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node


class PrintForever(Node):
    """Logs 'Printed N times.' every 0.5 s, N counting up from 0."""

    def __init__(self) -> None:
        super().__init__('print_forever')
        self.print_count: int = 0
        timer_period: float = 0.5  # seconds
        self.timer = self.create_timer(timer_period, self.timer_callback)

    def timer_callback(self) -> None:
        """Called by the executor every timer_period seconds."""
        self.get_logger().info(f'Printed {self.print_count} times.')
        self.print_count += 1


def main(args=None) -> None:
    """Spin the node until Ctrl+C.

    In Jazzy, Ctrl+C during rclpy.spin() can surface as KeyboardInterrupt or as
    ExternalShutdownException (the signal handler shut the context down first):
    both mean "the user asked us to stop", so both end the program quietly.
    """
    try:
        rclpy.init(args=args)
        node = PrintForever()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
