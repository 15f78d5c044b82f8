"""A node with a service server: /what_is_the_point answers what the point of a quote is (seed ch. 20.3)."""

import random

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from package_with_interfaces.srv import WhatIsThePoint


class WhatIsThePointServiceServerNode(Node):
    """Serves WhatIsThePoint: a point whose coordinates sum to 42 if, and only if, the quote is about life."""

    def __init__(self) -> None:
        super().__init__('what_is_the_point_service_server')
        self.service_server = self.create_service(
            srv_type=WhatIsThePoint,
            srv_name='/what_is_the_point',
            callback=self.what_is_the_point_service_callback)
        self.service_server_call_count: int = 0

    def what_is_the_point_service_callback(self,
                                           request: WhatIsThePoint.Request,
                                           response: WhatIsThePoint.Response) -> WhatIsThePoint.Response:
        """Fill and return the response for one request.

        'life' is looked for in the quote's text whatever its case ('Life', 'LIFE', ...).
        """
        if 'life' in request.quote.quote.lower():
            x = random.uniform(0.0, 42.0)
            y = random.uniform(0.0, 42.0 - x)
            z = 42.0 - (x + y)
        else:
            x = random.uniform(0.0, 100.0)
            y = random.uniform(0.0, 100.0)
            z = random.uniform(0.0, 100.0)
            if abs((x + y + z) - 42.0) < 1.0:  # a random 42 would give the wrong answer: move away from it
                x += 2.0
        response.point.x = x
        response.point.y = y
        response.point.z = z

        self.service_server_call_count += 1
        self.get_logger().info(
            f'Call number {self.service_server_call_count}: analysed '
            f"'{request.quote.quote}' -- {request.quote.philosopher_name}; "
            f'the point is {(x, y, z)}.')
        return response


def main(args=None) -> None:
    """Spin the node until Ctrl+C (KeyboardInterrupt or, in Jazzy, ExternalShutdownException)."""
    try:
        rclpy.init(args=args)
        node = WhatIsThePointServiceServerNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
