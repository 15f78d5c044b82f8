"""An action client: sends one MoveStraightIn2D goal, logs its feedback and its result, then ends.

The goal comes from the parameters x and y (metres). Nothing blocks: waiting for the
server, the goal's acceptance and its result are all callbacks of the executor.
"""

import rclpy
from action_msgs.msg import GoalStatus
from rclpy.action import ActionClient
from rclpy.action.client import ClientGoalHandle
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.task import Future

from package_with_interfaces.action import MoveStraightIn2D

#: What each terminal status is called (action_msgs/msg/GoalStatus), for the log.
STATUS_NAMES = {
    GoalStatus.STATUS_SUCCEEDED: 'SUCCEEDED',
    GoalStatus.STATUS_CANCELED: 'CANCELED',
    GoalStatus.STATUS_ABORTED: 'ABORTED',
}


class MoveStraightIn2DActionClientNode(Node):
    """Waits for /move_straight_in_2d, sends the goal (x, y) once, and sets ``done`` when it has ended."""

    def __init__(self) -> None:
        super().__init__('move_straight_in_2d_action_client')
        self.x = self.declare_parameter('x', 1.0).value
        self.y = self.declare_parameter('y', 0.5).value
        self.action_client = ActionClient(self, MoveStraightIn2D, '/move_straight_in_2d')
        self.done = False
        self.timer = self.create_timer(0.2, self.timer_callback)

    def timer_callback(self) -> None:
        """Until the server is there, say so (once a second); then send the goal once."""
        if not self.action_client.server_is_ready():
            self.get_logger().info('action server /move_straight_in_2d not available, waiting...',
                                   throttle_duration_sec=1.0)
            return
        self.timer.cancel()
        goal = MoveStraightIn2D.Goal()
        goal.desired_position.x = self.x
        goal.desired_position.y = self.y
        self.get_logger().info(f'Sending the goal ({self.x:.3f}, {self.y:.3f})')
        future = self.action_client.send_goal_async(goal, feedback_callback=self.feedback_callback)
        future.add_done_callback(self.goal_response_callback)

    def goal_response_callback(self, future: Future) -> None:
        """The server accepted or rejected the goal; when accepted, ask for its result."""
        goal_handle: ClientGoalHandle = future.result()
        if not goal_handle.accepted:
            self.get_logger().warning(f'Goal ({self.x:.3f}, {self.y:.3f}) rejected')
            self.done = True
            return
        self.get_logger().info('Goal accepted')
        goal_handle.get_result_async().add_done_callback(self.result_callback)

    def feedback_callback(self, feedback_message: MoveStraightIn2D.Impl.FeedbackMessage) -> None:
        """Log the distance still to go."""
        self.get_logger().info(f'Distance to goal: {feedback_message.feedback.distance_to_goal:.3f} m')

    def result_callback(self, future: Future) -> None:
        """Log the final position and how the goal ended, then let main() return."""
        response = future.result()
        status = STATUS_NAMES.get(response.status, f'status {response.status}')
        final = response.result.final_position
        self.get_logger().info(f'Goal {status}: final position ({final.x:.3f}, {final.y:.3f})')
        self.done = True


def main(args=None) -> None:
    """Spin until the goal has ended (or Ctrl+C)."""
    try:
        rclpy.init(args=args)
        node = MoveStraightIn2DActionClientNode()
        while rclpy.ok() and not node.done:
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
