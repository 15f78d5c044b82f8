"""A node that calls the function and the class of python_package_with_a_library."""

import random
import string

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from python_package_with_a_library.sample_python_library import SampleClass, sample_function_for_square_of_sum


class NodeThatUsesTheLibrary(Node):
    """Every 0.5 s: logs (a+b)**2 for random a, b, then the name of a randomly named SampleClass."""

    def __init__(self) -> None:
        super().__init__('node_that_uses_the_library')
        timer_period: float = 0.5  # seconds
        self.timer = self.create_timer(timer_period, self.timer_callback)

    def timer_callback(self) -> None:
        """Use the library's function and class once each."""
        a: float = random.uniform(0, 1)
        b: float = random.uniform(1, 2)
        c: float = sample_function_for_square_of_sum(a, b)
        self.get_logger().info(f'sample_function_for_square_of_sum({a},{b}) returned {c}.')

        random_name: str = ''.join(random.choice(string.ascii_letters) for _ in range(10))
        sample_class_with_random_name = SampleClass(name=random_name)
        self.get_logger().info(
            f'sample_class_with_random_name.get_name() returned {sample_class_with_random_name.get_name()}.')


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
