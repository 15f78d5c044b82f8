"""The steps of the ``actions-server`` grader (graders/actions_server.py), one function per check or group
of checks, and the lesson's contract values they and the grader's ``CHECKS`` share (chapters/actions-server/
CONTRACT.md). A helper of one lesson (the placement rule in ``ros2course.kit``'s docstring): the grader's own
action client (:class:`ros2course.kit.actions.GoalClient`) drives the learner's server through the goals the
grader's docstring lists, and the learner's script runs against it.

Positions are ``(x, y)`` tuples in metres, directions radians, times seconds (``time.time()`` for send stamps).
"""

from __future__ import annotations

import itertools
import math
import random
import time
from typing import Any

from ros2course import kit
from ros2course.kit import Session, Unmet, scripts
from ros2course.kit import actions as act

PACKAGE = "python_package_that_uses_the_actions"
EXECUTABLE = "move_straight_in_2d_action_server_node"
NODE = "move_straight_in_2d_action_server"
ACTION = "/move_straight_in_2d"
ACTION_TYPE = "package_with_interfaces/action/MoveStraightIn2D"
SPEED = 1.0  # metres per second (CONTRACT.md)
PERIOD = 0.1  # seconds between two feedback messages (CONTRACT.md)
MAX_DISTANCE = 2.0  # metres: goals farther than this from the point are rejected (CONTRACT.md)
#: metres from the point of the goal just over the limit (rejected): far enough past it that no rounding of the
#: point's position decides, near enough that a server with a looser limit (2.1 m) accepts it
JUST_OVER = 2.02
#: Metres: positions judged (the result, where a canceled goal stopped).
POSITION_TOLERANCE = 0.01
#: Metres: where the point is after a cancel or a first step, judged to one step and a half (one
#: more step may be taken while the request travels).
STEP_TOLERANCE = 1.5 * SPEED * PERIOD
#: Metres: a canceled goal's final_position against its last feedback ("as far from the goal as the last
#: feedback said": both are where the point is after its last step). Half a step: a feedback published before
#: its step (the distance the step starts from) is a step off (helper audit of issue 37; it was STEP_TOLERANCE).
LAST_FEEDBACK_TOLERANCE = 0.5 * SPEED * PERIOD
#: Metres: how far off the straight way from its start to the goal a canceled goal's final_position may be.
#: A correct server: a rounding error, plus where goal 1 really ended, which ``result`` judged to
#: POSITION_TOLERANCE of its goal (the grader's start of the way): a start that far off moves the straight
#: line by at most that much between the start and the goal, so twice it leaves a margin as large again. A
#: server whose steps do not point at the goal drifts off it: one whose x step is ``dx % distance * step``
#: (not ``dx / distance``) drifts about 0.075 m x |sin 2a| in the first three steps of the 1.6 m goal (a: the
#: way's angle from the x axis), caught unless the way runs within about 8 degrees of an axis (was 5 x
#: POSITION_TOLERANCE: caught only within 45 +- 30 degrees; that mutant survived the held-out sample of seed 18).
OFF_THE_WAY = 2 * POSITION_TOLERANCE
#: Seconds a goal of distance d may take: d / SPEED plus this (start-up and a loaded machine).
GOAL_SLACK = 3.0
#: Metres: goal 1 from (0, 0). Just under 1 m (with its coordinates rounded to 3 decimals, 0.9983 to
#: 0.9997 m): the step before the last leaves just under 0.1 m, so the last step is a full one and
#: every run judges the last feedback (0.0) and the landing (a server that skips either is 0.1 m off).
FIRST_DISTANCE = 0.999
#: Metres: the goal just within the limit that must be accepted (``accepts_within``). Not exactly
#: MAX_DISTANCE: a correct server's point may sit a rounding error (1e-16 m) off a goal it landed on,
#: and a goal exactly 2.0 m from where the grader believes the point is may then be 2.0 m and an ulp
#: from the server's point, rightly rejected; a limit wrongly put anywhere below 1.99 m is caught.
WITHIN_DISTANCE = 1.99
#: Metres: goal 3 (canceled) and goal 4 (preempted) from where the point is (see the module docstring).
CANCEL_DISTANCE = 1.6
PREEMPT_DISTANCE = 1.8
#: Goals the grader sends to see one canceled (or preempted): a goal that SUCCEEDED before the cancel
#: request reached the server (ERROR_GOAL_TERMINATED), or before the preempting goal was sent, is the
#: grader's lateness, and the next is canceled (preempted) sooner.
CANCEL_ATTEMPTS = 3
SCRIPT = "cli/action_move_straight.sh"
SCRIPT_TIMEOUT = 20.0  # seconds: three ros2 commands, about 1 s each to start, and a 0.5 m goal


def _point(x: float, y: float) -> Any:
    from geometry_msgs.msg import (  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
        Point,  # a wheel of the venv; graders load for CHECKS without ROS
    )

    return Point(x=x, y=y, z=0.0)


def _goal(action: Any, x: float, y: float) -> Any:
    goal = action.Goal()
    goal.desired_position = _point(x, y)
    return goal


def _xy(point: Any) -> tuple[float, float]:
    return point.x, point.y


def _finite_or(xy: tuple[float, float], fallback: tuple[float, float]) -> tuple[float, float]:
    """``xy`` when both are numbers, else ``fallback``: a server that accepted a NaN goal reports a NaN
    point for ever, and the next goals are placed from where a correct server would be instead."""
    return xy if all(math.isfinite(v) for v in xy) else fallback


def _show(xy: tuple[float, float]) -> str:
    return f"({xy[0]:.3f}, {xy[1]:.3f})"


def _distances(client: act.GoalClient, goal: act.Goal) -> list[tuple[float, float]]:
    """``(send stamp, distance_to_goal)`` of ``goal``'s feedback so far."""
    return [(stamp, feedback.distance_to_goal) for stamp, feedback in client.feedback(goal)]


def _wait_feedback(s: Session, client: act.GoalClient, goal: act.Goal, count: int, node: kit.StartedNode,
                   timeout: float) -> list[tuple[float, float]]:
    with s.phase("observe"):
        kit.wait_until(lambda: len(_distances(client, goal)) >= count or goal.result_future is not None
                       and goal.result_future.done(), timeout, abort=node.ended)
    return _distances(client, goal)


#: What each package's package.xml must declare (<depend>: build, export and run), CONTRACT.md.
DEPENDENCIES = {"package_with_interfaces": ("action_msgs",),
                PACKAGE: ("rclpy", "action_msgs", "package_with_interfaces")}


def depends(s: Session) -> None:
    """Record ``depends``: both package.xml declare what the lesson and its contract list (partial credit per name)."""
    seen, missing = [], []
    total = sum(len(needed) for needed in DEPENDENCIES.values())
    for package, needed in DEPENDENCIES.items():
        found = kit.source_package(s, package)
        if found is None and package != PACKAGE:
            # built beneath the workspace (an underlay, as dev validate builds the course's copy): not the learner's
            seen.append(f"{package}: not in src/ (not judged)")
            total -= len(needed)
            continue
        if found is None:
            missing += [f"{package}: no such package in src/"]
            seen.append(f"{package}: not found")
            continue
        deps = kit.declared_dependencies(found[1])
        lacking = [name for name in needed if name not in deps]
        missing += [f"{package}: {name}" for name in lacking]
        seen.append(f"{package} declares {', '.join(sorted(deps)) or 'nothing'}"
                    + (f" (missing {', '.join(lacking)})" if lacking else ""))
    s.record("depends", not missing, "; ".join(seen),
             "; ".join(f"{package}: " + ", ".join(f"<depend>{n}</depend>" for n in needed)
                       for package, needed in DEPENDENCIES.items()),
             fraction=max(0, total - len(missing)) / total)


def served(s: Session, client: act.GoalClient, node: kit.StartedNode) -> None:
    """Record ``action_served``: the node lists the action and the grader's client reaches it."""
    found = act.wait_for_action(s, node.name, "servers", ACTION, 5.0, abort=node.ended)
    ready = ACTION_TYPE in found.get(ACTION, []) and client.wait_for_server(3.0, abort=node.ended)
    shown = ", ".join(f"{name} [{', '.join(types)}]" for name, types in sorted(found.items())) or "none"
    observed = f"{node.name or 'no node'} serves the action(s): {shown}"
    if ACTION in found and not ready:
        observed += "; the grader's client of that type could not reach it (the action's fields differ?)"
    s.record("action_served", ready, f"{observed}; {kit.process_state(node.proc)}" if not ready else observed,
             f"{ACTION} [{ACTION_TYPE}] (ros2 node info: Action Servers)")
    s.require("action_served")


def first_goal(s: Session, action: Any, client: act.GoalClient,
                node: kit.StartedNode) -> tuple[tuple[float, float], float]:
    """Goal 1 (FIRST_DISTANCE from the origin): goal_accepted, feedback, feedback_rate, speed, result.

    Returns where the point is believed to be afterwards, and the goal's direction (radians).
    """
    angle = s.random.uniform(0.0, 2.0 * math.pi)  # the same files get the same goals (Session.random)
    target = (round(FIRST_DISTANCE * math.cos(angle), 3), round(FIRST_DISTANCE * math.sin(angle), 3))
    distance = math.hypot(*target)
    goal = client.send(_goal(action, *target))
    s.record("goal_accepted", bool(goal.accepted),
             f"the goal {_show(target)} ({distance:.3f} m from the start (0, 0)) was "
             + {True: "accepted", False: "rejected", None: "not answered"}[goal.accepted]
             + (f": {goal.why}" if goal.why else ""),
             f"the goal {_show(target)} accepted")
    s.require("goal_accepted")
    began = time.monotonic()
    client.wait_result(goal, distance / SPEED + GOAL_SLACK, abort=node.ended)
    _judge_feedback(s, client, goal, distance, time.monotonic() - began)
    expected = f"status SUCCEEDED, final_position {_show(target)} ± {POSITION_TOLERANCE} m"
    if goal.status is None:
        s.record("result", False, f"{goal.why}; {kit.process_state(node.proc)}", expected)
        return target, angle
    final = _xy(goal.result.final_position)
    ok = goal.status == act.SUCCEEDED and math.dist(final, target) <= POSITION_TOLERANCE
    s.record("result", ok, f"status {act.status_name(goal.status)}, final_position {_show(final)}", expected)
    return target, angle  # where a correct server put the point (the result itself is judged above)


def _judge_feedback(s: Session, client: act.GoalClient, goal: act.Goal, distance: float, waited: float) -> None:
    """Record ``feedback``, ``feedback_rate`` and ``speed`` from goal 1's feedback messages."""
    with s.phase("observe"):  # the last feedback may arrive just after the result
        kit.wait_until(lambda: any(d <= POSITION_TOLERANCE for _, d in _distances(client, goal)), kit.LATE_DELIVERY)
    samples = _distances(client, goal)
    steps = int(distance / (SPEED * PERIOD))
    expected = (f"about {steps} feedback messages, distance_to_goal falling at every one, from about "
                f"{distance - SPEED * PERIOD:.2f} m (the point starts at (0, 0)) to a last 0.0 (± {POSITION_TOLERANCE})")
    if not samples:
        s.record("feedback", False, f"no feedback in {waited:.1f} s (status {act.status_name(goal.status)})",
                 expected)
        return
    values = [d for _, d in samples]
    # the first message seen is at most one step (and those taken since the goal was sent) below the distance
    # from (0, 0): a point that started elsewhere is farther from goal 1, or nearer
    lowest = distance - STEP_TOLERANCE - SPEED * max(0.0, samples[0][0] - goal.sent)
    shown = ", ".join(f"{d:.3f}" for d in values[:4]) + (f", ..., {values[-1]:.3f}" if len(values) > 4 else "")
    falling = all(b < a for a, b in itertools.pairwise(values))
    # the last is 0.0 within the tolerance on either side: a distance is never negative (held-out seed 23 left a
    # last feedback of -1.0 alive while only its upper bound was judged)
    ends_at_zero = abs(values[-1]) <= POSITION_TOLERANCE
    ok = (falling and len(values) >= steps // 2 and lowest <= values[0] <= distance + POSITION_TOLERANCE
          and ends_at_zero)
    why = "" if ok else (": it does not fall at every step" if not falling else
                         f": only {len(values)} message(s)" if len(values) < steps // 2 else
                         ": it does not end at 0 (a last feedback of 0.0 once on the goal)"
                         if not ends_at_zero else
                         f": it starts above the {distance:.3f} m from (0, 0) to go" if values[0] > distance else
                         f": it starts below {lowest:.3f} m, nearer than the {distance:.3f} m from (0, 0) allows "
                         "(did the point start at (0, 0)?)")
    s.record("feedback", ok, f"{len(values)} feedback message(s), distance_to_goal {shown}{why}", expected)
    stamps = [t for t, _ in samples]
    kit.rate(s, "feedback_rate", stamps[:-1] if len(stamps) > steps else stamps, period=PERIOD,
             needed=min(steps, 6), waited=waited, noun="feedback message", source="the feedback messages' send stamps")
    moving = [(t, d) for t, d in samples if d > POSITION_TOLERANCE]
    expected = f"distance_to_goal falling at {SPEED} m/s ± {kit.RATE_TOLERANCE:.0%} (least squares over the send stamps)"
    if len(moving) < 3:
        s.record("speed", False, f"only {len(moving)} feedback message(s) while moving", expected)
        return
    slope = _slope(moving)
    s.record("speed", abs(-slope - SPEED) <= kit.RATE_TOLERANCE * SPEED,
             f"the distance falls at {-slope:.3f} m/s over {len(moving)} feedback messages", expected,
             window=(moving[0][0], moving[-1][0]))


def _slope(points: list[tuple[float, float]]) -> float:
    """Least-squares slope of ``(t, value)`` points (value units per second)."""
    n = len(points)
    mean_t = sum(t for t, _ in points) / n
    mean_v = sum(v for _, v in points) / n
    spread = sum((t - mean_t) ** 2 for t, _ in points)
    return sum((t - mean_t) * (v - mean_v) for t, v in points) / spread if spread else 0.0


def rejects(s: Session, action: Any, client: act.GoalClient,
             start: tuple[float, float]) -> tuple[float, float]:
    """Record ``rejects``: goals 3 m from the point along y and along x, one 2.6 m from it across the
    origin (only 1.6 m from the origin: a server measuring from (0, 0) instead of from the point accepts
    it), one :data:`JUST_OVER` the limit straight away from the origin (a server whose limit is looser than
    the lesson's 2.0 m accepts it), one with a NaN x and one with a NaN y are all rejected. ``start`` is the
    point after goal 1, 1 m from the origin.

    Returns where the point is afterwards: ``start``, or where a goal the server wrongly accepted
    stopped when the grader canceled it (its result's final_position; how far it got depends on how
    soon the cancel arrived, so ``position_kept`` is judged from there, never from ``start``).

    The far goals go from the point towards the origin's side along one axis each, whatever goal 1's
    random direction: the distance along the other axis is 0, so a server that ignores it, or mixes
    the goal's and the point's coordinates on it, accepts one of them in every run."""
    far_y = (round(start[0], 3), round(start[1] - math.copysign(3.0, start[1]), 3))
    far_x = (round(start[0] - math.copysign(3.0, start[0]), 3), round(start[1], 3))
    across = (round(-1.6 * start[0], 3), round(-1.6 * start[1], 3))
    norm = math.hypot(*start) or 1.0
    just_over = (round(start[0] + JUST_OVER * start[0] / norm, 3), round(start[1] + JUST_OVER * start[1] / norm, 3))
    cases = [(f"{_show(far_y)}, 3 m away", far_y),
             (f"{_show(far_x)}, 3 m away", far_x),
             (f"{_show(across)}, {math.dist(across, start):.1f} m away (but {math.hypot(*across):.1f} m from the "
              "origin)", across),
             (f"{_show(just_over)}, {math.dist(just_over, start):.2f} m away (just over the {MAX_DISTANCE} m limit)",
              just_over),
             ("(nan, 0.5)", (math.nan, 0.5)),
             ("(0.5, nan)", (0.5, math.nan))]
    seen, wrong = [], 0
    for label, xy in cases:
        goal = client.send(_goal(action, *xy))
        if goal.accepted:
            wrong += 1
            start = _cancel_at_once(client, goal, 3.0, start)  # it must not drive off (none is over 3 m away)
        verdict = _answer(goal)
        seen.append(f"{label}: {verdict}")
        if goal.accepted is None:
            wrong += 1
    s.record("rejects", wrong == 0, "; ".join(seen), "all rejected (GoalResponse.REJECT)",
             fraction=(len(cases) - wrong) / len(cases))
    return start


def accepts_within(s: Session, action: Any, client: act.GoalClient,
                    start: tuple[float, float]) -> tuple[float, float]:
    """Record ``accepts_within``: a goal WITHIN_DISTANCE from the point, straight away from the origin, is
    accepted; the grader then cancels it at once (the point moves a step or two, not 2 m). Sent after
    goal 4 (:func:`preempt`), so the goals before it are placed as they always were.

    Returns where the point is afterwards: the canceled goal's final_position (as :func:`rejects`
    does for a wrongly accepted goal), or ``start`` when the goal was not accepted.
    """
    norm = math.hypot(*start) or 1.0
    target = (round(start[0] + WITHIN_DISTANCE * start[0] / norm, 3), round(start[1] + WITHIN_DISTANCE * start[1] / norm, 3))
    goal = client.send(_goal(action, *target))
    observed = (f"the goal {_show(target)}, {math.dist(target, start):.3f} m from the point {_show(start)}, was "
                + _answer(goal))
    s.record("accepts_within", bool(goal.accepted), observed, f"accepted: only goals more than {MAX_DISTANCE} m "
             "away are rejected")
    return _cancel_at_once(client, goal, WITHIN_DISTANCE, start) if goal.accepted else start


def _answer(goal: act.Goal) -> str:
    """What the server answered to ``goal``: accepted, rejected or not answered (why)."""
    return {True: "accepted", False: "rejected", None: f"not answered ({goal.why})"}[goal.accepted]


def _cancel_at_once(client: act.GoalClient, goal: act.Goal, distance: float,
                    start: tuple[float, float]) -> tuple[float, float]:
    """Cancel the accepted ``goal`` (``distance`` metres from ``start``, where the point was) and wait for its
    result; returns where the point stopped (its final_position), or ``start`` when no finite one came."""
    client.cancel(goal)
    client.wait_result(goal, 3.0 + distance / SPEED)
    return _finite_or(_xy(goal.result.final_position), start) if goal.result is not None else start


def cancel(s: Session, action: Any, client: act.GoalClient, node: kit.StartedNode,
            start: tuple[float, float], heading: float) -> list[tuple[float, float]]:
    """Goal 2, canceled after three feedback messages: position_kept, cancel_accepted, canceled.

    ``heading``: the direction of goal 1 from the origin (radians). Returns where the point is
    believed to be afterwards: one position, or two when the server's last feedback and its result
    disagree (a wrong server; :func:`preempt` places its goal so that either is right).
    """
    # CANCEL_DISTANCE from where goal 1 ended, at right angles to goal 1's way: from the origin it is
    # hypot(1, 1.6) = 1.89 m away, so a server that reset the point shows it in its first feedback
    d = CANCEL_DISTANCE
    late_tries: list[str] = []
    # where the way starts is known when the server's goal 1 ended on its goal and the goal's first feedback
    # starts there (position_kept); else only the distances are judged (one bug, one lost check)
    known_start = _passed(s, "result")
    for attempt in range(CANCEL_ATTEMPTS):
        target = (round(start[0] - d * math.sin(heading), 3), round(start[1] + d * math.cos(heading), 3))
        goal = client.send(_goal(action, *target))
        if not goal.accepted:
            reason = f"the goal {_show(target)}, {d} m from {_show(start)}, was not accepted ({goal.why or 'rejected'})"
            for check_id in ("position_kept", "cancel_accepted")[attempt > 0:]:
                s.record(check_id, False, reason, "accepted")
            return [start]
        # the first try waits three feedback messages (the point moved); a try again cancels at the first
        first = _wait_feedback(s, client, goal, 1 if attempt else 3, node, 3.0)
        if not attempt:
            _position_kept(s, first, d, start, target)
        accepted, why = client.cancel(goal)
        asked = time.time()
        if accepted:
            client.wait_result(goal, 2.0, abort=node.ended)
            time.sleep(2 * PERIOD)  # a server that keeps moving sends feedback now
        elif goal.cancel_code == act.GOAL_TERMINATED:
            client.wait_result(goal, d / SPEED + GOAL_SLACK, abort=node.ended)
        late = _grader_was_late(client, goal, target, asked, accepted)
        if not late or attempt + 1 == CANCEL_ATTEMPTS:
            break
        # the grader lost the race, not the server (a loaded machine delivers feedback late): try again
        # from where the goal ended (the server's own result), cancelling sooner
        late_tries.append(late)
        start, heading = _finite_or(_xy(goal.result.final_position), target), heading + math.pi / 2
        known_start = True
    tried = _tried(late_tries)
    s.record("cancel_accepted", bool(accepted),
             "the cancel request was accepted" + tried if accepted else f"cancel: {why}; the goal then ended "
             + act.status_name(client.wait_result(goal, d / SPEED + GOAL_SLACK, abort=node.ended).status) + tried,
             "the goal listed among goals_canceling in the answer")
    if not accepted:
        client.wait_result(goal, d / SPEED + GOAL_SLACK, abort=node.ended)
        return [_finite_or(_xy(goal.result.final_position), target) if goal.result is not None else target]
    late = [d for t, d in _distances(client, goal) if t > asked + 1.5 * PERIOD]
    samples = _distances(client, goal)
    expected = (f"status CANCELED, final_position where the point stopped (short of the goal by the last "
                f"distance_to_goal ± {LAST_FEEDBACK_TOLERANCE:.2f} m, within {OFF_THE_WAY} m of the straight way "
                "from where it started), no feedback after the cancel")
    if goal.status is None:
        s.record("canceled", False, f"{goal.why} after the cancel; {kit.process_state(node.proc)}", expected)
        return [target]
    final = _xy(goal.result.final_position)
    short = math.dist(final, target)
    last = samples[-1][1] if samples else d
    # where the point stopped by the server's own last feedback: the next goal starts there
    stopped = (target[0] - (target[0] - start[0]) / d * last, target[1] - (target[1] - start[1]) / d * last)
    problems = []
    if goal.status != act.CANCELED:
        problems.append(f"status {act.status_name(goal.status)}")
    # not (... <= tolerance): a NaN position or distance is never "within" it (abs(nan - x) > t is False)
    if not abs(short - last) <= LAST_FEEDBACK_TOLERANCE or short < POSITION_TOLERANCE:
        problems.append(f"final_position {_show(final)} is {short:.3f} m from the goal, the last feedback said "
                        f"{last:.3f}")
    elif known_start and _passed(s, "position_kept") and all(map(math.isfinite, final)) and (off := _off_the_way(start, target, final)) > OFF_THE_WAY:
        # the right distance from the goal, but off the straight way there: each step moves the point
        # towards the goal (contract: 0.1 m towards it), so where it stopped is on the segment
        problems.append(f"final_position {_show(final)} is {off:.3f} m off the straight way from {_show(start)} "
                        f"to the goal (a point moved towards the goal stays on it)")
    if late:
        problems.append(f"{len(late)} feedback message(s) sent after the cancel (down to {late[-1]:.3f} m)")
    s.record("canceled", not problems, "; ".join(problems) if problems else
             f"CANCELED at {_show(final)}, {short:.3f} m short of the goal, nothing sent after it", expected)
    if not math.isfinite(last):
        return [_finite_or(final, target)]
    # a server whose feedback or result is wrong (those checks failed above) leaves the point's place
    # uncertain: goal 4 must then be valid from both, or its verdict would depend on a random angle
    return [stopped, final] if all(map(math.isfinite, final)) and math.dist(stopped, final) > STEP_TOLERANCE \
        else [stopped]


def _grader_was_late(client: act.GoalClient, goal: act.Goal, target: tuple[float, float], asked: float,
                     accepted: bool) -> str:
    """Why the grader must cancel ``goal`` again, sooner ('' when it must not): its cancel request (answered at
    ``asked``, ``time.time()`` seconds; ``accepted`` or not) came too late to say anything about the server.

    Two ways, both seen on CI's loaded machine (feedback delivered more than a second late):

    * refused with ERROR_GOAL_TERMINATED, as it must be, because the goal had already SUCCEEDED;
    * accepted, and the goal ended CANCELED within POSITION_TOLERANCE of ``target``, as its last feedback said,
      with nothing sent after the request: a correct server's point can end a step a few millimetres short of
      the goal and wait a PERIOD before its last, and the request arrived then (CI saw a 1.6 m goal CANCELED
      0.000 m from its end). A server that ignores the cancel until the goal cannot show this: it sends
      feedback after the request (and a try again cancels at the first feedback).
    """
    samples = _distances(client, goal)
    if not accepted:
        if goal.cancel_code != act.GOAL_TERMINATED or goal.status != act.SUCCEEDED or goal.result is None:
            return ""
        return (f"the goal {_show(target)} had SUCCEEDED when the cancel request arrived "
                f"({len(samples)} feedback messages seen)")
    if goal.status != act.CANCELED or goal.result is None or not samples:
        return ""
    final = _xy(goal.result.final_position)
    if not all(map(math.isfinite, final)) or math.dist(final, target) >= POSITION_TOLERANCE:
        return ""
    if samples[-1][1] >= POSITION_TOLERANCE or any(t > asked + 1.5 * PERIOD for t, _ in samples):
        return ""
    return (f"the goal {_show(target)} was CANCELED {math.dist(final, target):.3f} m from its end: the cancel "
            f"request arrived in the point's last step ({len(samples)} feedback messages seen)")


def _passed(s: Session, check_id: str) -> bool:
    """True when ``check_id`` was recorded and passed."""
    return check_id in s.results and s.results[check_id].passed


def _off_the_way(start: tuple[float, float], target: tuple[float, float], point: tuple[float, float]) -> float:
    """Metres from ``point`` to the line through ``start`` and ``target`` (its cross-track distance)."""
    ux, uy = target[0] - start[0], target[1] - start[1]
    length = math.hypot(ux, uy)
    return abs((point[0] - start[0]) * uy - (point[1] - start[1]) * ux) / length if length else math.dist(start, point)


def _tried(late_tries: list[str]) -> str:
    """What the grader tried again after, for the observed text ('' when nothing)."""
    return f" (tried again after: {'; '.join(late_tries)})" if late_tries else ""


def _position_kept(s: Session, first: list[tuple[float, float]], d: float, start: tuple[float, float],
                   target: tuple[float, float]) -> None:
    """Record ``position_kept`` from the ``(stamp, distance_to_goal)`` feedback of a goal ``d`` metres from
    ``start``, where the last goal ended: its first distance is at most ``d`` (a server that reset the point
    to the origin reports the distance from there)."""
    expected = (f"the first feedback of a goal {d} m from where the last ended: distance_to_goal within "
                f"{STEP_TOLERANCE:.2f} m below {d}")
    if not first:
        s.record("position_kept", False, f"no feedback for the goal {_show(target)}", expected)
        return
    d0 = first[0][1]
    s.record("position_kept", d - STEP_TOLERANCE <= d0 <= d + POSITION_TOLERANCE,
             f"goal {_show(target)} from {_show(start)}: first distance_to_goal {d0:.3f} m"
             + ("" if d0 <= d + POSITION_TOLERANCE else
                f" (from the origin it would be {math.hypot(*target) - SPEED * PERIOD:.3f})"
                if math.isfinite(d0) else
                ": the point is no longer a number (an accepted goal with a NaN x or y moved it there)"),
             expected)


def _away_from(rng: random.Random, places: list[tuple[float, float]], distance: float) -> tuple[float, float]:
    """A goal ``distance`` metres from the first of ``places``, and from the second too when the two are
    between 5 cm and ``2 * distance`` apart (where the two circles meet, on a random side); otherwise in a
    random direction from the first."""
    a = places[0]
    if len(places) > 1 and 0.05 < (gap := math.dist(a, places[1])) < 2 * distance:
        b = places[1]
        mid = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)
        h = rng.choice((-1.0, 1.0)) * math.sqrt(distance ** 2 - (gap / 2) ** 2)
        ux, uy = (b[0] - a[0]) / gap, (b[1] - a[1]) / gap
        return round(mid[0] - h * uy, 3), round(mid[1] + h * ux, 3)
    angle = rng.uniform(0.0, 2.0 * math.pi)
    return round(a[0] + distance * math.cos(angle), 3), round(a[1] + distance * math.sin(angle), 3)


def preempt(s: Session, action: Any, client: act.GoalClient, node: kit.StartedNode,
             places: list[tuple[float, float]]) -> list[str]:
    """Record ``preempted``: a goal PREEMPT_DISTANCE away is aborted by a goal back to the start, which succeeds.

    ``places``: where the point may be (:func:`cancel`); the goal is PREEMPT_DISTANCE from each, the
    start is the first. Returns the goals the server still executes after the grader asked to cancel
    them (its executor busy with them: it can take no other request).
    """
    late_tries: list[str] = []
    for attempt in range(CANCEL_ATTEMPTS):
        far = _away_from(s.random, places, PREEMPT_DISTANCE)
        back = (round(places[0][0], 3), round(places[0][1], 3))
        expected = ("the first goal ABORTED once the second is accepted (a goal rejected meanwhile leaves it running); "
                    "the second starts where the first left the point and SUCCEEDED, final_position "
                    f"{_show(back)} ± {POSITION_TOLERANCE} m")
        first = client.send(_goal(action, *far))
        if not first.accepted:
            s.record("preempted", False, f"the goal {_show(far)} ({PREEMPT_DISTANCE} m away) was not accepted"
                     + _tried(late_tries), expected)
            return []
        # the first try waits three feedback messages (the point moved); a try again sends at the first
        _wait_feedback(s, client, first, 1 if attempt else 3, node, 3.0)
        refused = _rejected_meanwhile(s, action, client, first, places, far, node)
        second = client.send(_goal(action, *back))
        client.wait_result(first, PREEMPT_DISTANCE / SPEED + GOAL_SLACK, abort=node.ended)
        client.wait_result(second, PREEMPT_DISTANCE / SPEED + GOAL_SLACK, abort=node.ended)
        # the grader lost the race, not the server: by its feedback the first goal had (nearly) arrived
        # before the second was sent (a loaded machine delivers feedback late): try again from where the
        # second goal took the point, sending sooner
        arrived = [d for stamp, d in _distances(client, first) if stamp < second.sent and d <= STEP_TOLERANCE]
        if not (arrived and first.status == act.SUCCEEDED and second.status == act.SUCCEEDED
                and attempt + 1 < CANCEL_ATTEMPTS):
            break
        late_tries.append(f"the goal {_show(far)} had reached its end ({arrived[0]:.3f} m to go) when the "
                          "second goal was sent")
        places = [back]
    observed = [f"first goal {_show(far)}: {act.status_name(first.status)}"]
    ok = True
    if refused:
        observed.append(refused)
        ok = False
    if second.accepted:
        final = _xy(second.result.final_position) if second.result is not None else None
        observed.append(f"second goal {_show(back)}: {act.status_name(second.status)}"
                        + (f" at {_show(final)}" if final else ""))
        ok = ok and (first.status == act.ABORTED and second.status == act.SUCCEEDED and final is not None
                     and math.dist(final, back) <= POSITION_TOLERANCE)
        lost = _progress_lost(client, first, second, places, far)
        if lost:
            observed.append(lost)
            ok = False
        # a first goal that succeeded before the second was accepted did not run alongside it
        if first.status == act.SUCCEEDED and first.ended is not None and first.ended <= second.sent + PERIOD:
            observed.append("the first goal ended before the second was accepted (was the server able to take "
                            "a goal while executing one?)")
    else:
        ok = False
        observed.append(f"second goal {_show(back)}: {'rejected' if second.accepted is False else second.why}")
    observed[-1] += _tried(late_tries)
    s.record("preempted", ok, "; ".join(observed), expected)
    stuck = []
    for goal in (first, second):  # goals still running (two loops fighting over the point) end here
        if goal.accepted and goal.status is None:
            client.cancel(goal)
            if client.wait_result(goal, 1.0, abort=node.ended).status is None:
                stuck.append(_show(_xy(goal.request.desired_position)))
    return stuck


def cli(s: Session, node: kit.StartedNode, start: tuple[float, float]) -> None:
    """Run the learner's script with a goal 0.5 m from the point; judge what it printed."""
    path = scripts.script(s, "cli_script", SCRIPT)
    if node.ended():
        raise Unmet(f"the server is no longer running: {kit.process_state(node.proc)}")
    angle = s.random.uniform(0.0, 2.0 * math.pi)
    target = (round(start[0] + 0.5 * math.cos(angle), 3), round(start[1] + 0.5 * math.sin(angle), 3))
    run = scripts.run_script(s, path, timeout=SCRIPT_TIMEOUT, args=[f"{target[0]}", f"{target[1]}"],
                             daemon_sees=[f"/{NODE}", f"{ACTION}/_action/send_goal"])
    scripts.printed(s, "cli_list", run, [ACTION], f"the action {ACTION}", "ros2 action list", whole_lines=True)
    scripts.printed(s, "cli_info", run, [f"Action: {ACTION}", "Action servers: 1", f"    /{NODE}"],
                    f"that /{NODE} serves {ACTION}", f"ros2 action info {ACTION}")
    needles = ["Feedback:", "distance_to_goal:", "Goal finished with status: SUCCEEDED",
               f"x: {target[0]}", f"y: {target[1]}"]
    sent = scripts.printed(s, "cli_send_goal", run, needles, f"the goal ({target[0]}, {target[1]}) sent, its "
                           "feedback and its result", f"ros2 action send_goal --feedback {ACTION} {ACTION_TYPE} "
                           "\"{desired_position: {x: $1, y: $2}}\"")
    if sent:
        _sequence(s, run)


#: Metres from every point of the executing goal's way to the goal :func:`_rejected_meanwhile` sends: well over
#: MAX_DISTANCE, wherever on its way the point is.
REJECTED_MARGIN = MAX_DISTANCE + 1.5


def _to_segment(point: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    """Metres from ``point`` to the segment from ``a`` to ``b``."""
    ux, uy = b[0] - a[0], b[1] - a[1]
    length2 = ux * ux + uy * uy
    t = 0.0 if not length2 else max(0.0, min(1.0, ((point[0] - a[0]) * ux + (point[1] - a[1]) * uy) / length2))
    return math.dist(point, (a[0] + t * ux, a[1] + t * uy))


def _rejected_meanwhile(s: Session, action: Any, client: act.GoalClient, running: act.Goal,
                        places: list[tuple[float, float]], far: tuple[float, float], node: kit.StartedNode) -> str:
    """While ``running`` (a goal from one of ``places`` to ``far``) executes, send a goal the server must reject
    (over :data:`REJECTED_MARGIN` m from every point of that way); ``running`` must go on: the lesson aborts the
    old goal when a new one is *accepted*, and a rejected goal never runs (the independent review of stop 82
    got full marks with a server that aborted the executing goal in goal_callback, before deciding).

    Returns what was wrong, or "" (also when the probe is not sent: ``rejects`` failed, so a goal this far may
    be accepted and would move the point, or no such goal is found, or ``running`` already ended).
    """
    if not _passed(s, "rejects") or not running.accepted or running.status is not None:
        return ""
    a = places[0]
    away = math.dist(a, far) or 1.0
    target = (round(a[0] - (far[0] - a[0]) / away * (REJECTED_MARGIN + 0.5), 3),
              round(a[1] - (far[1] - a[1]) / away * (REJECTED_MARGIN + 0.5), 3))
    if min(_to_segment(target, p, far) for p in places) < REJECTED_MARGIN:
        return ""
    probe = client.send(_goal(action, *target))
    if probe.accepted:  # judged by rejects; cancelled at once, so that the preemption is judged as before
        client.cancel(probe)
        client.wait_result(probe, 1.0, abort=node.ended)
        return ""
    with s.phase("observe"):  # a server that aborts in goal_callback has done so before it answered
        client.wait_result(running, 2 * PERIOD, abort=node.ended)
    if running.status is None:
        return ""
    return (f"the goal {_show(target)}, sent while the first executed, was rejected, and the first then ended "
            f"{act.status_name(running.status)}: a rejected goal must leave the executing one running (abort the "
            "old goal in handle_accepted_callback, not in goal_callback)")


def _progress_lost(client: act.GoalClient, first: act.Goal, second: act.Goal, places: list[tuple[float, float]],
                   far: tuple[float, float]) -> str:
    """What shows that the aborted ``first`` goal's progress was lost, or "": ``second`` (back to ``places[0]``)
    must start from where ``first`` left the point (the lesson: the point stays where each goal leaves it). By
    ``first``'s last feedback the point was ``d`` m short of ``far`` on its way from one of ``places``; the
    second goal's first feedback must then say nearly as far from its goal (two steps of slack: the two goals
    may overlap by a step). Judged only when that way left the point over 0.35 m from the second goal (the
    independent review of stop 82 got full marks with a server that restored the point an aborted goal
    started from, so a goal back there 'succeeded' without moving)."""
    if first.status != act.ABORTED or second.status != act.SUCCEEDED:
        return ""
    left = [d for _, d in _distances(client, first)]
    went = [d for _, d in _distances(client, second)]
    if not left or not all(math.isfinite(d) for d in left + went):
        return ""
    went = went or [0.0]  # it succeeded without a feedback message: it had nowhere to go
    back = places[0]
    span = math.dist(back, far) or 1.0
    ahead = []
    for p in places:
        length = math.dist(p, far) or 1.0
        t = min(left) / length  # the point: min(left) m short of far, on the way from p
        ahead.append(math.dist((far[0] + (p[0] - far[0]) * t, far[1] + (p[1] - far[1]) * t), back))
    gap = min(ahead)
    if gap < 0.35 or span < 0.35:
        return ""
    if went[0] >= gap - 2 * STEP_TOLERANCE:
        return ""
    return (f"the first goal's feedback had left the point about {gap:.2f} m from {_show(back)}, but the second "
            f"goal's first feedback said {went[0]:.3f} m to go: the aborted goal's progress was lost (the point "
            "must stay where each goal leaves it, an aborted one too)")


def _sequence(s: Session, run: Any) -> None:
    """Record ``cli_sequence``: the outputs of list, info and send_goal come in that order, and the script
    ended by itself before its deadline."""
    lines = [line.rstrip() for line in run.stdout.splitlines()]
    listed = lines.index(ACTION) if ACTION in lines else -1
    info = next((i for i, line in enumerate(lines) if line.startswith("Action servers:")), -1)
    sent = next((i for i, line in enumerate(lines) if line.startswith(("Sending goal", "Feedback:"))), -1)
    problems = []
    if not listed < info < sent:
        order = sorted([(listed, "ros2 action list"), (info, "ros2 action info"), (sent, "ros2 action send_goal")])
        problems.append("their outputs come in the order " + ", ".join(name for _, name in order))
    if run.timed_out:
        problems.append(f"it was still running after {SCRIPT_TIMEOUT:.0f} s and was stopped")
    s.record("cli_sequence", not problems, "; ".join(problems) or "list, info, then send_goal, and it ended by itself",
             f"ros2 action list, ros2 action info {ACTION}, then ros2 action send_goal, and the script ends by "
             f"itself (within {SCRIPT_TIMEOUT:.0f} s)")
