"""A sensor stream: a Temperature on /temperature every 0.1 s with the sensor-data QoS profile."""

import math

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from sensor_msgs.msg import Temperature


class SensorPublisherNode(Node):
    """Publishes a simulated temperature at 10 Hz, BEST_EFFORT, VOLATILE, KEEP_LAST 5."""

    def __init__(self) -> None:
        super().__init__('sensor_publisher_node')
        # TODO 2: a plain depth (10) means RELIABLE, VOLATILE, KEEP_LAST 10. A sensor stream uses
        #         the preset rclpy.qos.qos_profile_sensor_data (BEST_EFFORT, VOLATILE, KEEP_LAST 5).
        self.temperature_publisher = self.create_publisher(
            msg_type=Temperature,
            topic='/temperature',
            qos_profile=10)
        self.count = 0
        self.timer = self.create_timer(0.1, self.timer_callback)

    def timer_callback(self) -> None:
        """Publish one reading: 21.5 degrees plus a slow wave."""
        msg = Temperature()
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.header.frame_id = 'temperature_sensor'
        msg.temperature = 21.5 + 0.5 * math.sin(self.count / 10.0)
        msg.variance = 0.01
        self.temperature_publisher.publish(msg)
        self.count += 1


def main(args=None) -> None:
    """Spin the node until Ctrl+C (KeyboardInterrupt or, in Jazzy, ExternalShutdownException)."""
    try:
        rclpy.init(args=args)
        node = SensorPublisherNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
