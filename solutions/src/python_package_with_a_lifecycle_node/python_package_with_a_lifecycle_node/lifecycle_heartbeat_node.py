"""A managed (lifecycle) node that publishes a heartbeat only while it is active (lesson: lifecycle-node).

States and transitions (design.ros2.org/articles/node_lifecycle.html):

    unconfigured --configure--> inactive --activate--> active
    active --deactivate--> inactive --cleanup--> unconfigured
    any primary state --shutdown--> finalized

Drive it from a second terminal with ``ros2 lifecycle get/list/set /lifecycle_heartbeat ...``.
"""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.lifecycle.publisher import LifecyclePublisher
from rclpy.timer import Timer
from std_msgs.msg import String


class LifecycleHeartbeatNode(LifecycleNode):
    """Publishes 'Heartbeat N' on /heartbeat every 0.2 s (5 Hz), but only in the active state."""

    def __init__(self) -> None:
        super().__init__('lifecycle_heartbeat')
        # Nothing is created here: a managed node starts unconfigured, with no publisher and no timer.
        self.heartbeat_publisher: LifecyclePublisher | None = None
        self.timer: Timer | None = None
        self.count: int = 0

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """unconfigured -> inactive: create the lifecycle publisher and the timer."""
        self.heartbeat_publisher = self.create_lifecycle_publisher(String, 'heartbeat', 10)
        self.timer = self.create_timer(0.2, self.timer_callback)
        self.count = 0
        self.get_logger().info('on_configure: publisher and timer created.')
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """inactive -> active: the base class enables the lifecycle publisher."""
        self.get_logger().info('on_activate: publishing.')
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """active -> inactive: the base class disables the lifecycle publisher (its publish() drops)."""
        self.get_logger().info('on_deactivate: no longer publishing.')
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """inactive -> unconfigured: destroy what on_configure created, so configure can run again."""
        self._destroy_entities()
        self.get_logger().info('on_cleanup: publisher and timer destroyed.')
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Any primary state -> finalized: release everything (shutdown may come while active)."""
        self._destroy_entities()
        self.get_logger().info('on_shutdown: finalized.')
        return TransitionCallbackReturn.SUCCESS

    def _destroy_entities(self) -> None:
        if self.timer is not None:
            self.destroy_timer(self.timer)
            self.timer = None
        if self.heartbeat_publisher is not None:
            self.destroy_lifecycle_publisher(self.heartbeat_publisher)
            self.heartbeat_publisher = None

    def timer_callback(self) -> None:
        """Publish one heartbeat; while the node is inactive the lifecycle publisher drops it."""
        self.heartbeat_publisher.publish(String(data=f'Heartbeat {self.count}'))
        self.count += 1


def main(args=None) -> None:
    """Spin the node until Ctrl+C (it starts unconfigured: nothing happens until a transition)."""
    try:
        rclpy.init(args=args)
        node = LifecycleHeartbeatNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
