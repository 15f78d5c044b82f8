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
        # TODO 1: a Buffer (it keeps the last 10 s of every transform) and a TransformListener that
        #         fills it (it subscribes to /tf and /tf_static for you): keep both as attributes.
        self.timer = self.create_timer(PERIOD, self.timer_callback)

    def timer_callback(self) -> None:
        """Look the transform up at Time() (the latest one available)."""
        # TODO 2: t = self.buffer.lookup_transform('world', 'target', Time()) raises a
        #         TransformException while nobody broadcasts those frames: catch it and log a warning
        #         (self.get_logger().warning(...)) instead of letting the node crash.
        # TODO 3: log where target is: f'target in world: x={p.x:.3f} y={p.y:.3f} z={p.z:.3f}'
        #         with p = t.transform.translation.
        pass


def main(args=None):
    try:
        rclpy.init(args=args)
        node = FrameListener()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
