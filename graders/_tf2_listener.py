"""tf2-listener's own steps: the grader as the tf2 tree (its transforms on /tf) and the positions it draws."""

from __future__ import annotations

import threading

from ros2course.kit import Session
from ros2course.kit import topics_services as ts


class Broadcast:
    """The grader's own ``parent -> child`` on /tf (at :attr:`position`, metres; none while it is None), sent every
    ``period`` seconds from a thread, with the :attr:`edges` beside it ((parent, child) pairs 1 m apart), as
    ``tf2_ros.TransformBroadcaster`` publishes ``tf2_msgs/msg/TFMessage`` (without importing tf2_ros, whose C
    extension needs the underlay's libtf2 on the grading process's library path). Stopped when the part ends."""

    def __init__(self, s: Session, tf_message: type, transform_type: type, parent: str, child: str,
                 period: float) -> None:
        self.s, self.tf_message, self.transform_type = s, tf_message, transform_type
        self.parent, self.child, self.period = parent, child, period
        self.publisher = s.graph.node.create_publisher(tf_message, "/tf", ts.reliable_qos(100))
        self.position: tuple[float, float, float] | None = None
        self.edges: list[tuple[str, str]] = []
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, name="ros2course-tf-broadcast", daemon=True)
        self.thread.start()
        s.on_close(self.close)

    def _run(self) -> None:
        while not self.stop.wait(self.period):
            edges = [(self.parent, self.child, self.position)] if self.position is not None else []
            edges += [(parent, child, (1.0, 0.0, 0.0)) for parent, child in self.edges]
            if not edges:
                continue
            stamp = self.s.graph.node.get_clock().now().to_msg()
            transforms = []
            for parent, child, position in edges:
                t = self.transform_type()
                t.header.stamp = stamp
                t.header.frame_id, t.child_frame_id = parent, child
                t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = position
                t.transform.rotation.w = 1.0
                transforms.append(t)
            self.publisher.publish(self.tf_message(transforms=transforms))

    def close(self) -> None:
        self.stop.set()
        self.thread.join(timeout=2.0)


def random_position(s: Session, far_from: tuple[float, float, float] | None = None) -> tuple[float, float, float]:
    """Three decimals each in [-3, 3] m, every coordinate at least 0.5 m from ``far_from``'s (Session.random).

    Each coordinate's third decimal is 4, 5 or 6, so a position logged with two decimals is at least 0.004 m off
    (more than tf2-listener's tolerance, 0.002 m) whatever the draw: the lesson asks for three (helper audit of issue 37: with
    any third decimal, a two-decimal log passed about one grading in eight, by the draw)."""
    while True:
        found = tuple(round(s.random.uniform(-3.0, 3.0), 3) for _ in range(3))
        if min(abs(v) for v in found) > 0.2 and all(round(abs(v) * 1000) % 10 in (4, 5, 6) for v in found) and (
                far_from is None or all(abs(a - b) > 0.5 for a, b in zip(found, far_from))):
            return found
