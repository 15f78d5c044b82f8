"""A node that logs how many times it has logged, twice a second."""

import rclpy
from rclpy.node import Node


class PrintForever(Node):
    """Logs 'Printed N times.' every 0.5 s, N counting up from 0."""

    def __init__(self) -> None:
        # TODO 1: give the node its name, 'print_forever', through super().__init__()
        super().__init__('TODO')
        # TODO 2: a counter starting at 0
        # TODO 3: a timer calling self.timer_callback every 0.5 s

    def timer_callback(self) -> None:
        """Called by the executor every timer period."""
        # TODO 4: log 'Printed N times.' with the node's logger (not print()), then count up


def main(args=None) -> None:
    """Spin the node until Ctrl+C."""
    # TODO 5: Ctrl+C must end the program with exit code 0 and no traceback.
    #         In Jazzy rclpy.spin() may raise ExternalShutdownException on Ctrl+C.
    rclpy.init(args=args)
    node = PrintForever()
    rclpy.spin(node)


if __name__ == '__main__':
    main()
