"""A node with a service client: asks /what_is_the_point twice a second, without blocking."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.task import Future

# TODO 7: import the WhatIsThePoint service generated from package_with_interfaces


class WhatIsThePointServiceClientNode(Node):
    """Calls WhatIsThePoint every 0.5 s with call_async and logs each point it gets back."""

    def __init__(self) -> None:
        # TODO 8: the node's name is what_is_the_point_service_client
        super().__init__('TODO')
        # TODO 9: a client of WhatIsThePoint for /what_is_the_point,
        #         and a timer calling self.timer_callback every 0.5 s

    def timer_callback(self) -> None:
        """Send one request and return at once."""
        # TODO 10: while the service is not ready (service_is_ready()), log that you
        #          are waiting for it and return.
        # TODO 11: build a WhatIsThePoint.Request (fill request.quote), send it with
        #          call_async and attach self.process_response with add_done_callback.
        #          Never wait for the answer here.

    def process_response(self, future: Future) -> None:
        """Called by the executor when the future is done."""
        # TODO 12: log the point in future.result() (it can be None, e.g. when cancelled)


def main(args=None) -> None:
    """Spin the node until Ctrl+C."""
    try:
        rclpy.init(args=args)
        node = WhatIsThePointServiceClientNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
