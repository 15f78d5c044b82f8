"""A monitor that receives both the sensor stream and the latched configuration."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSProfile,
    ReliabilityPolicy,
    qos_profile_sensor_data,
)
from sensor_msgs.msg import Temperature
from std_msgs.msg import String


class SensorMonitorNode(Node):
    """Logs every configuration and every temperature reading it receives."""

    def __init__(self) -> None:
        super().__init__('sensor_monitor_node')
        # A subscription asks for QoS; the publisher offers it. BEST_EFFORT asks for the least, so
        # it matches the sensor's BEST_EFFORT stream (a RELIABLE request never would).
        self.temperature_subscription = self.create_subscription(
            msg_type=Temperature,
            topic='/temperature',
            callback=self.temperature_callback,
            qos_profile=qos_profile_sensor_data)
        # TRANSIENT_LOCAL on this side too: only then does the publisher replay its last message
        # to us when we start after it was published.
        latched = QoSProfile(
            history=HistoryPolicy.KEEP_LAST,
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.config_subscription = self.create_subscription(
            msg_type=String,
            topic='/sensor_config',
            callback=self.config_callback,
            qos_profile=latched)

    def temperature_callback(self, msg: Temperature) -> None:
        """Log one reading with two decimals."""
        self.get_logger().info(f'Temperature: {msg.temperature:.2f}')

    def config_callback(self, msg: String) -> None:
        """Log the configuration as it came."""
        self.get_logger().info(f'Config: {msg.data}')


def main(args=None) -> None:
    """Spin the node until Ctrl+C (KeyboardInterrupt or, in Jazzy, ExternalShutdownException)."""
    try:
        rclpy.init(args=args)
        node = SensorMonitorNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
