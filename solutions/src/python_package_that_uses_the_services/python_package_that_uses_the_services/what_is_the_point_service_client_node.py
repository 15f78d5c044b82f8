"""A node with a service client: asks /what_is_the_point twice a second, without blocking (seed ch. 20.5)."""

import random

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.task import Future

from package_with_interfaces.srv import WhatIsThePoint


class WhatIsThePointServiceClientNode(Node):
    """Calls WhatIsThePoint every 0.5 s with call_async and logs each point it gets back."""

    def __init__(self) -> None:
        super().__init__('what_is_the_point_service_client')
        self.service_client = self.create_client(
            srv_type=WhatIsThePoint,
            srv_name='/what_is_the_point')
        self.future: Future | None = None
        timer_period: float = 0.5  # seconds
        self.timer = self.create_timer(timer_period_sec=timer_period, callback=self.timer_callback)

    def timer_callback(self) -> None:
        """Send one request and return at once: the answer arrives later, in process_response."""
        # Wait for the server without blocking: until it is there, each tick only says so
        # (at most once a second). Ctrl+C stays responsive, unlike a wait_for_service()
        # loop in __init__, which runs before rclpy.spin() can handle the shutdown.
        if not self.service_client.service_is_ready():
            self.get_logger().info(f'service {self.service_client.srv_name} not available, waiting...',
                                   throttle_duration_sec=1.0)
            return

        request = WhatIsThePoint.Request()
        if random.uniform(0.0, 1.0) < 0.5:
            request.quote.quote = 'I wonder about the Ultimate Question of Life, the Universe, and Everything.'
            request.quote.philosopher_name = 'Creators of Deep Thought'
            request.quote.id = 1979
        else:
            request.quote.quote = '[...] your living... it is always potatoes. I dream of potatoes.'
            request.quote.philosopher_name = 'a young Maltese potato farmer'
            request.quote.id = 2013

        if self.future is not None and not self.future.done():
            # The previous answer is late: give up on it rather than pile up requests.
            self.future.cancel()
            self.get_logger().warning('The previous call took more than 0.5 s: cancelled it. '
                                      'Is the service server still alive?')
        self.future = self.service_client.call_async(request)
        self.future.add_done_callback(self.process_response)

    def process_response(self, future: Future) -> None:
        """Called by the executor when the future is done (answered, or cancelled)."""
        if future.cancelled():
            return
        response = future.result()
        if response is not None:
            point = (response.point.x, response.point.y, response.point.z)
            self.get_logger().info(f'We have thus received the point of our quote: {point}')


def main(args=None) -> None:
    """Spin the node until Ctrl+C (KeyboardInterrupt or, in Jazzy, ExternalShutdownException)."""
    try:
        rclpy.init(args=args)
        node = WhatIsThePointServiceClientNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
