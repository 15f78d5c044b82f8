"""Grader for ``actions-server`` (contract in chapters/actions-server/CONTRACT.md).

Black-box, as ``ros2 action send_goal`` would: the grader's own action client
(:class:`ros2course.kit.actions.GoalClient`) sends the learner's server four goals
in a row, the point it simulates carrying over from one to the next:

1. a goal 1 m away (just under: its last step is a full one, so a server that skips the last
   feedback (0.0) or does not land on the goal shows it in every run): accepted, feedback every
   0.1 s with the distance falling at 1 m/s (a least-squares fit over the feedback messages' send
   stamps), ending at 0.0, the result the goal itself and the status SUCCEEDED;
2. goals 3 m away along y and along x, one 2.6 m away across the origin, one 2.02 m away (just
   over the 2.0 m limit), and goals with a NaN x and a NaN y: all rejected; then one 1.99 m away (just within the 2.0 m limit, straight away
   from the origin): accepted, and canceled at once;
3. a goal 1.6 m from where goal 1 ended, canceled after three feedback messages:
   its first feedback shows where the point started (the position is kept), the
   cancel is accepted, the goal ends CANCELED short of the goal and nothing moves
   after it;
4. a goal 1.8 m away, then after three feedback messages a second goal: the first
   ends ABORTED (one goal at a time), the second SUCCEEDED;
5. a goal 1.99 m away (just within the 2.0 m limit, straight away from the origin): accepted,
   and canceled at once.

Goals 3 and 4 are long (1.6 s and 1.8 s at the contract's speed) although the grader
acts after their first 0.3 s: on a loaded machine the grader may see the third
feedback message late, and a goal that had already ended by then could not be
canceled or preempted (CI saw a 0.8 m goal end before its cancel arrived). When it still could
not (CI saw a 1.6 m goal SUCCEED before the cancel request, answered ERROR_GOAL_TERMINATED, as it
must be), or the cancel arrived in the point's last step (CI saw a 1.6 m goal CANCELED 0.000 m from
its end, its last feedback a few millimetres, nothing sent after the request), the grader was late, not the
server: it tries again with a new goal, acting at its first feedback message (``CANCEL_ATTEMPTS``;
tests/test_grader_lateness.py).

Then the learner's ``cli/action_move_straight.sh X Y`` runs against the same server
(``ros2 action list``, ``info``, ``send_goal --feedback``), with a goal only the
grader knows.
"""

from __future__ import annotations

from ros2course import kit
from ros2course.kit import Check, Session, Unmet, checks
from ros2course.kit import actions as act

from . import _actions_server as steps
from ._actions_server import ACTION, ACTION_TYPE, EXECUTABLE, MAX_DISTANCE, NODE, PACKAGE, PERIOD, SCRIPT, SPEED, \
    WITHIN_DISTANCE

#: Seconds the contract needs the server watched (benchmarks/all_lessons.py): goal 1 (1 m at SPEED),
#: three feedback messages then two periods of silence after the cancel, three messages of goal 3 and
#: goal 4's way back (0.3 m), the script's 0.5 m goal.
WINDOW = 1.0 / SPEED + 5 * PERIOD + 6 * PERIOD + 0.5 / SPEED

RUN = ("executable",)
SERVED = ("action_served",)
CHECKS = [
    Check("build", "The packages build with colcon", 1),
    Check("depends", "The package.xml files declare the action's dependencies", 1,
          "package_with_interfaces/package.xml: <depend>action_msgs</depend> (actions need it); "
          f"{PACKAGE}/package.xml: <depend>rclpy</depend>, <depend>action_msgs</depend>, "
          "<depend>package_with_interfaces</depend>"),
    *checks.started("", PACKAGE, EXECUTABLE, NODE),
    Check("action_served", f"It serves the action {ACTION} [{ACTION_TYPE}]", 2,
          f"ActionServer(self, MoveStraightIn2D, '{ACTION}', execute_callback=...) in __init__; the action "
          "must be in package_with_interfaces (action/MoveStraightIn2D.action, listed in rosidl_generate_interfaces)",
          needs=RUN),
    Check("goal_accepted", "A goal 1 m away is accepted", 1,
          "goal_callback returns GoalResponse.ACCEPT for a goal with finite coordinates within 2 m", needs=SERVED),
    Check("feedback", "While it moves, it publishes feedback: distance_to_goal falls at every step, to 0", 2,
          "after each step: feedback.distance_to_goal = the distance still to go; "
          "goal_handle.publish_feedback(feedback); when the goal is one step away or closer, land on it and "
          "publish a last feedback of 0.0", needs=("goal_accepted",)),
    Check("feedback_rate", f"One feedback message every {PERIOD} s ({1 / PERIOD:.0f} Hz)", 1,
          f"sleep {PERIOD} s between two steps (time.sleep({PERIOD}) in execute_callback)", needs=("feedback",)),
    Check("speed", f"The point moves at {SPEED} m/s (the distance falls {SPEED * PERIOD} m per step)", 2,
          f"move {SPEED * PERIOD} m towards the goal at each step: position += direction * SPEED * PERIOD",
          needs=("feedback",)),
    Check("result", "The goal ends SUCCEEDED, its result the goal itself", 2,
          "when the last step lands on the goal: goal_handle.succeed(), and return a Result whose final_position "
          "is where the point is (put the point exactly on the goal when it is one step away or closer: "
          "compare distances with a step, never == on floats)", needs=("goal_accepted",)),
    Check("rejects", f"Goals more than {MAX_DISTANCE} m away, or with an x or a y not finite, are rejected", 2,
          "in goal_callback: return GoalResponse.REJECT when math.isfinite() fails for x or for y, or when the goal "
          f"is more than {MAX_DISTANCE} m from the point (measure from where the point is now, not from the origin)",
          needs=SERVED),
    Check("position_kept", "The next goal starts where the last one ended", 1,
          "keep the point's position in the node (self.position), not in execute_callback: it must survive "
          "from one goal to the next", needs=("goal_accepted",)),
    Check("cancel_accepted", "A cancel request for the executing goal is accepted", 1,
          "pass cancel_callback= to ActionServer, returning CancelResponse.ACCEPT (the default rejects every "
          "cancel); spin with a MultiThreadedExecutor and a ReentrantCallbackGroup, or the cancel request "
          "waits until execute_callback returns", needs=("goal_accepted",)),
    Check("canceled", "The canceled goal ends CANCELED where the point stopped, and the point stops", 2,
          "in the loop of execute_callback: if goal_handle.is_cancel_requested: goal_handle.canceled() and return "
          "a Result with the position reached", needs=("cancel_accepted",)),
    Check("preempted", "A new goal aborts the one executing (ABORTED), then succeeds itself", 2,
          "in handle_accepted_callback: if the previous goal handle is_active, call its abort(), then "
          "goal_handle.execute(); in the loop, stop when not goal_handle.is_active", needs=("goal_accepted",)),
    Check("accepts_within", f"A goal {WITHIN_DISTANCE} m away (within {MAX_DISTANCE} m of the point) is accepted", 1,
          f"reject only goals MORE than {MAX_DISTANCE} m from the point: if distance > {MAX_DISTANCE}: reject, "
          "else accept (a smaller limit rejects goals the lesson says to accept)", needs=SERVED),
    Check("cli_script", f"{SCRIPT} exists and is valid bash", 1, part="cli", needs=SERVED),
    Check("cli_list", f"It lists the actions: {ACTION}", 1, "ros2 action list", part="cli", needs=("cli_script",)),
    Check("cli_info", f"It shows who serves {ACTION}", 1, f"ros2 action info {ACTION}", part="cli",
          needs=("cli_script",)),
    Check("cli_send_goal", "It sends the goal given as its arguments, prints the feedback and the result", 2,
          f"ros2 action send_goal --feedback {ACTION} {ACTION_TYPE} \"{{desired_position: {{x: $1, y: $2}}}}\"",
          part="cli", needs=("cli_script",)),
    Check("cli_sequence", "It runs list, info, then send_goal, in that order, and ends by itself", 1,
          f"three commands, one after the other, in this order: ros2 action list; ros2 action info {ACTION}; "
          "ros2 action send_goal --feedback ... (nothing that keeps running after it)",
          part="cli", needs=("cli_list", "cli_info", "cli_send_goal")),
    checks.ctrl_c("sigint_exit", "the server", 1, needs=RUN),
]



def grade(s: Session) -> None:
    """Start the server, send it four goals, then run the learner's script against it."""
    steps.depends(s)
    action = s.interface_type("package_with_interfaces", "action", "MoveStraightIn2D")
    path = kit.executable(s, "executable", PACKAGE, EXECUTABLE)
    client = act.GoalClient(s, action, ACTION)  # before the node starts: no feedback is missed
    node = kit.start_node(s, "node_name", path, NODE, sigint_check="sigint_exit", need_node=False)
    stuck: list[str] = []
    stop = [(0.0, 0.0)]  # where the point may be when a step before the cancel raised Unmet
    with s.part("server"):
        steps.served(s, client, node)
        start, heading = steps.first_goal(s, action, client, node)
        start = steps.rejects(s, action, client, start)
        stop = steps.cancel(s, action, client, node, start, heading)
        stuck = steps.preempt(s, action, client, node, stop)
        # last of the server's goals: its point after the cancel is the server's own (a server that resets the
        # point shows it on goal 3, which this one would hide by moving the point it reports)
        stop = [steps.accepts_within(s, action, client, stop[0])]
    with s.part("cli"):
        unmet = s.unmet_need("cli_script")
        if unmet is not None:
            raise Unmet(unmet)
        if stuck:
            raise Unmet(f"the server still executes the goal(s) {', '.join(stuck)} and answers no cancel: "
                        "every thread of its executor is busy")
        steps.cli(s, node, stop[0])  # where the last goal (accepts_within's, canceled) left the point
