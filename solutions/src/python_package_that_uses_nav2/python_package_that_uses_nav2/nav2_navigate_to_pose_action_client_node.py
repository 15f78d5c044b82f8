"""Sends nav2 one goal on /navigate_to_pose, logs its feedback and how it ended, then ends.

Nothing blocks: waiting for the server, the goal's acceptance and its result are all
callbacks of the executor.
"""

import rclpy
from action_msgs.msg import GoalStatus
from geometry_msgs.msg import PoseStamped
from nav2_msgs.action import NavigateToPose
from rclpy.action import ActionClient
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.task import Future

ACTION = '/navigate_to_pose'
FRAME = 'map'
GOAL_X, GOAL_Y = 1.0, -1.0  # metres, in the map frame; facing along the map's x axis

#: What each terminal status is called (action_msgs/msg/GoalStatus), for the log.
STATUS_NAMES = {
    GoalStatus.STATUS_SUCCEEDED: 'SUCCEEDED',
    GoalStatus.STATUS_CANCELED: 'CANCELED',
    GoalStatus.STATUS_ABORTED: 'ABORTED',
}


class Nav2NavigateToPoseActionClient(Node):
    """Waits for /navigate_to_pose, sends the goal once, and sets ``done`` when it has ended."""

    def __init__(self) -> None:
        super().__init__('nav2_navigate_to_pose_action_client')
        self.action_client = ActionClient(self, NavigateToPose, ACTION)
        self.done = False
        self.timer = self.create_timer(0.2, self.timer_callback)

    def timer_callback(self) -> None:
        """Until the server is there, say so (once a second); then send the goal once."""
        if not self.action_client.server_is_ready():
            self.get_logger().info(f'action server {ACTION} not available, waiting...', throttle_duration_sec=1.0)
            return
        self.timer.cancel()
        goal = NavigateToPose.Goal()
        goal.pose = self.goal_pose()
        goal.behavior_tree = ''  # nav2's default behaviour tree
        self.get_logger().info(f'Sending the goal ({GOAL_X:.2f}, {GOAL_Y:.2f}) in {FRAME}')
        future = self.action_client.send_goal_async(goal, feedback_callback=self.feedback_callback)
        future.add_done_callback(self.goal_response_callback)

    def goal_pose(self) -> PoseStamped:
        """The goal, stamped now with the node's clock."""
        pose = PoseStamped()
        pose.header.stamp = self.get_clock().now().to_msg()
        pose.header.frame_id = FRAME
        pose.pose.position.x = GOAL_X
        pose.pose.position.y = GOAL_Y
        pose.pose.orientation.w = 1.0
        return pose

    def goal_response_callback(self, future: Future) -> None:
        """nav2 accepted or rejected the goal; when accepted, ask for its result."""
        goal_handle = future.result()
        if not goal_handle.accepted:
            self.get_logger().warning('Goal rejected by nav2')
            self.done = True
            return
        self.get_logger().info('Goal accepted')
        goal_handle.get_result_async().add_done_callback(self.result_callback)

    def feedback_callback(self, feedback_message: NavigateToPose.Impl.FeedbackMessage) -> None:
        """Log the distance still to go."""
        self.get_logger().info(f'Distance remaining: {feedback_message.feedback.distance_remaining:.3f} m')

    def result_callback(self, future: Future) -> None:
        """Log how the goal ended, with nav2's error code and message, then let main() return."""
        response = future.result()
        status = STATUS_NAMES.get(response.status, f'status {response.status}')
        result = response.result
        self.get_logger().info(f'Goal {status}: error_code {result.error_code}, error_msg "{result.error_msg}"')
        self.done = True


def main(args=None) -> None:
    """Spin until the goal has ended (or Ctrl+C)."""
    try:
        rclpy.init(args=args)
        node = Nav2NavigateToPoseActionClient()
        while rclpy.ok() and not node.done:
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
