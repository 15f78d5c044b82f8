"""A monitor that receives both the sensor stream and the latched configuration."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from sensor_msgs.msg import Temperature
from std_msgs.msg import String


class SensorMonitorNode(Node):
    """Logs every configuration and every temperature reading it receives."""

    def __init__(self) -> None:
        super().__init__('sensor_monitor_node')
        # TODO 6: this requests RELIABLE (a plain depth), which a BEST_EFFORT sensor never offers:
        #         request what the sensor offers (rclpy.qos.qos_profile_sensor_data).
        self.temperature_subscription = self.create_subscription(
            msg_type=Temperature,
            topic='/temperature',
            callback=self.temperature_callback,
            qos_profile=10)
        # TODO 7: this is VOLATILE: a configuration published before this node started never
        #         arrives. Request the configuration publisher's latched profile (TRANSIENT_LOCAL).
        self.config_subscription = self.create_subscription(
            msg_type=String,
            topic='/sensor_config',
            callback=self.config_callback,
            qos_profile=10)

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
