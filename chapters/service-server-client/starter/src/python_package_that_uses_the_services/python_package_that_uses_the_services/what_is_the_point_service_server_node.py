"""A node with a service server: /what_is_the_point answers what the point of a quote is."""

import random

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

# TODO 3: import the WhatIsThePoint service generated from package_with_interfaces


class WhatIsThePointServiceServerNode(Node):
    """Serves WhatIsThePoint: a point whose coordinates sum to 42 if, and only if, the quote is about life."""

    def __init__(self) -> None:
        # TODO 4: the node's name is what_is_the_point_service_server
        super().__init__('TODO')
        # TODO 5: a service server of WhatIsThePoint called /what_is_the_point,
        #         calling self.what_is_the_point_service_callback

    def what_is_the_point_service_callback(self, request, response):
        """Fill and return the response for one request."""
        # TODO 6: if request.quote.quote contains 'life' in any case ('Life', 'LIFE', ...),
        #         make x + y + z == 42; otherwise make sure it is not 42.
        x = random.uniform(0.0, 100.0)
        y = random.uniform(0.0, 100.0)
        z = random.uniform(0.0, 100.0)
        response.point.x = x
        response.point.y = y
        response.point.z = z
        return response


def main(args=None) -> None:
    """Spin the node until Ctrl+C."""
    try:
        rclpy.init(args=args)
        node = WhatIsThePointServiceServerNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
