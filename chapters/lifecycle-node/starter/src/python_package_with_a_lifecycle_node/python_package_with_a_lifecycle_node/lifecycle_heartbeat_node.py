"""A heartbeat publisher to turn into a managed (lifecycle) node (lesson: lifecycle-node).

Right now it is a plain Node: it publishes from the moment it starts, and
`ros2 lifecycle` cannot drive it (it has no change_state/get_state services).
Follow the TODOs.
"""

# TODO: from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from std_msgs.msg import String


# TODO: subclass LifecycleNode instead of Node.
class LifecycleHeartbeatNode(Node):
    """Should publish 'Heartbeat N' on /heartbeat every 0.2 s (5 Hz), but only while active."""

    def __init__(self) -> None:
        super().__init__('lifecycle_heartbeat')
        # TODO: create nothing here. Set self.heartbeat_publisher and self.timer to None, and
        #       create them in on_configure (a *lifecycle* publisher: self.create_lifecycle_publisher).
        self.heartbeat_publisher = self.create_publisher(String, 'heartbeat', 10)
        self.timer = self.create_timer(0.2, self.timer_callback)
        self.count: int = 0

    # TODO: on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
    #       create the lifecycle publisher and the timer, return TransitionCallbackReturn.SUCCESS.

    # TODO: on_activate / on_deactivate: log something, then return super().on_activate(state) /
    #       super().on_deactivate(state) (the base class switches the lifecycle publisher on and off).

    # TODO: on_cleanup: destroy the timer (self.destroy_timer) and the publisher
    #       (self.destroy_lifecycle_publisher), set both back to None, return SUCCESS.

    # TODO: on_shutdown: the same as on_cleanup for whatever still exists (shutdown may come while active).

    def timer_callback(self) -> None:
        """Publish one heartbeat."""
        self.heartbeat_publisher.publish(String(data=f'Heartbeat {self.count}'))
        self.count += 1


def main(args=None) -> None:
    """Spin the node until Ctrl+C."""
    try:
        rclpy.init(args=args)
        node = LifecycleHeartbeatNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
