"""Where is `target`, seen from `world`? A tf2 listener that copes with frames not known yet."""

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.time import Time
from tf2_ros import Buffer, TransformException, TransformListener

PERIOD = 0.5  # seconds between two lookups


class FrameListener(Node):
    """Looks world -> target up every 0.5 s and logs where target is, or why it cannot tell yet."""

    def __init__(self) -> None:
        super().__init__('frame_listener')
        self.buffer = Buffer()  # the last 10 s of every transform, filled by the listener
        self.listener = TransformListener(self.buffer, self)  # subscribes to /tf and /tf_static
        self.timer = self.create_timer(PERIOD, self.timer_callback)

    def timer_callback(self) -> None:
        """Look the transform up at Time() (the latest one available); never let a lookup error end the node."""
        try:
            t = self.buffer.lookup_transform('world', 'target', Time())
        except TransformException as exc:
            self.get_logger().warning(f'world -> target not available yet: {exc}')
            return
        p = t.transform.translation
        self.get_logger().info(f'target in world: x={p.x:.3f} y={p.y:.3f} z={p.z:.3f}')


def main(args=None):
    try:
        rclpy.init(args=args)
        node = FrameListener()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
