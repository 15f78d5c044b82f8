"""A node that calls the function and the class of python_package_with_a_library."""

import random
import string

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

# TODO 1: import SampleClass and sample_function_for_square_of_sum from
#         python_package_with_a_library.sample_python_library


class NodeThatUsesTheLibrary(Node):
    """Every 0.5 s: logs (a+b)**2 for random a, b, then the name of a randomly named SampleClass."""

    def __init__(self) -> None:
        super().__init__('node_that_uses_the_library')
        # TODO 2: a timer calling self.timer_callback every 0.5 s

    def timer_callback(self) -> None:
        """Use the library's function and class once each."""
        # TODO 3: a random float a in [0, 1] and b in [1, 2] (random.uniform), c from the library's
        #         function; log: sample_function_for_square_of_sum(a,b) returned c.
        # TODO 4: a new random name of ten ASCII letters (string.ascii_letters), a SampleClass with
        #         that name; log: sample_class_with_random_name.get_name() returned NAME.
        pass


def main(args=None) -> None:
    """Spin the node until Ctrl+C (KeyboardInterrupt or, in Jazzy, ExternalShutdownException)."""
    try:
        rclpy.init(args=args)
        node = NodeThatUsesTheLibrary()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
