"""A latched configuration: /sensor_config, RELIABLE, TRANSIENT_LOCAL, KEEP_LAST 1."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from std_msgs.msg import String


class ConfigPublisherNode(Node):
    """Publishes 'units: <units>' once at start and again whenever the parameter units changes."""

    def __init__(self) -> None:
        super().__init__('config_publisher_node')
        self.declare_parameter('units', 'celsius')
        # TODO 3: a latched profile instead of the plain depth: QoSProfile with KEEP_LAST, depth 1,
        #         RELIABLE and TRANSIENT_LOCAL (rclpy.qos), so that a subscription that starts
        #         later still gets the current configuration, and only that one.
        self.config_publisher = self.create_publisher(
            msg_type=String,
            topic='/sensor_config',
            qos_profile=10)
        # TODO 4: publish again whenever the parameter units is set:
        #         self.add_post_set_parameters_callback(self.parameters_changed)
        self.publish_config()

    def publish_config(self) -> None:
        """Publish the current configuration."""
        units = self.get_parameter('units').get_parameter_value().string_value
        self.config_publisher.publish(String(data=f'units: {units}'))
        self.get_logger().info(f'Published the configuration units: {units}')

    def parameters_changed(self, parameters) -> None:
        """Called after parameters were set (ros2 param set): publish the new configuration."""
        # TODO 5: if a parameter named 'units' is among `parameters`, publish the configuration


def main(args=None) -> None:
    """Spin the node until Ctrl+C (KeyboardInterrupt or, in Jazzy, ExternalShutdownException)."""
    try:
        rclpy.init(args=args)
        node = ConfigPublisherNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
