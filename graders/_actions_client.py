"""The steps of the ``actions-client`` grader (graders/actions_client.py): one function per run of the learner's
client (goal, aborted, rejected, interrupted), and the lesson's contract values they and the grader's ``CHECKS``
share (chapters/actions-client/CONTRACT.md). A helper of one lesson (the placement rule in ``ros2course.kit``'s
docstring): the grader plays the action server (:class:`ros2course.kit.actions.StandInActionServer`) and judges
the client from its /rosout records and how its process ends.

Goal coordinates are metres, times seconds.
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable
from typing import Any

from ros2course import kit
from ros2course.kit import Session, Unmet
from ros2course.kit import actions as act
from ros2course.kit.console import log_texts
from ros2course.kit.records import names_status
from ros2course.kit.topics_services import numbers_in

from ros2course.kit import services

PACKAGE = "python_package_that_uses_the_actions"
EXECUTABLE = "move_straight_in_2d_action_client_node"
NODE = "move_straight_in_2d_action_client"
ACTION = "/move_straight_in_2d"
#: Seconds the client runs without a server before the grader's appears.
WAIT_WINDOW = 3.0
#: Seconds the server stays missing after the client's first "waiting" record: time for a client that
#: says so at most once a second to say it three times (a client that says it at every 0.2 s tick: 13).
THROTTLE_WINDOW = 2.5
#: Seconds between two "waiting" records (the lesson: at most once a second); a record or two more than
#: THROTTLE_WINDOW / WAIT_PERIOD + 1 is forgiven (a timer that catches up after a late tick).
WAIT_PERIOD = 1.0
#: Seconds a client may take to end by itself once its goal has ended.
END_TIMEOUT = 3.0
#: Seconds for the log records the grader looks for (one goal lasts under a second).
LOG_TIMEOUT = 5.0
#: Metres: a logged number matches a value the grader sent when it is this close (3 decimals printed).
NUMBER_TOLERANCE = 0.0006
PERIOD = 0.1  # seconds between the grader's feedback messages
#: What a record pretending a rejected goal ended says (a status, a result).
PRETENDS = re.compile(r"succe|abort|cancel|unknown|status|final|result", re.IGNORECASE)
#: What a record treating a rejected goal as accepted says (the code after a forgotten `return`, which then asks
#: for a result the goal never has: helper audit of issue 37).
ACCEPTED = re.compile(r"(?<!not )(?<!n't )\baccept", re.IGNORECASE)


def _goal_xy(s: Session) -> tuple[float, float]:
    """A goal for the learner's client to send: x in [0.3, 0.9], y in [-0.9, -0.3] m (Session.random)."""
    return round(s.random.uniform(0.3, 0.9), 3), round(s.random.uniform(-0.9, -0.3), 3)


def _params(xy: tuple[float, float]) -> list[str]:
    return ["--ros-args", "-p", f"x:={xy[0]}", "-p", f"y:={xy[1]}"]


def _gone(proc: kit.LearnerProcess) -> Callable[[], bool]:
    """True once ``proc`` has been dead for :data:`kit.LATE_DELIVERY` s: the records it logged just before
    exiting are still on their way to the grader until then."""
    def gone() -> bool:
        return proc.poll() is not None and time.monotonic() - (proc.ended_at or 0.0) > kit.LATE_DELIVERY

    return gone


def _has(text: str, value: float) -> bool:
    return any(abs(number - value) <= NUMBER_TOLERANCE for number in numbers_in(text))


def _records(rosout: Any, proc: kit.LearnerProcess) -> list[str]:
    """The client's log records (its node's logger), oldest first, on one line each: /rosout's, then those its
    console holds after them (a client that logs its result and exits at once can lose that record on /rosout:
    :mod:`ros2course.kit.console`)."""
    return log_texts(rosout, NODE, proc)


def _last(rosout: Any, proc: kit.LearnerProcess, count: int = 3) -> str:
    return " | ".join(text[:80] for text in _records(rosout, proc)[-count:]) or "no log records"


def _result_script(action: Any, final: tuple[float, float], distances: list[float], status: int) -> act.Script:
    feedback = []
    for distance in distances:
        message = action.Feedback()
        message.distance_to_goal = distance
        feedback.append(message)
    result = action.Result()
    result.final_position.x, result.final_position.y = final
    return act.Script(accept=True, feedback=feedback, result=result, status=status, period=PERIOD)


def interrupted_run(s: Session, path: Any) -> None:
    """sigint_exit: Ctrl+C while the client waits for a server that never comes (judged as the part ends,
    :func:`kit.ctrl_c_once_it_logs`)."""
    kit.ctrl_c_once_it_logs(s, "sigint_exit", lambda suffix: _started(
        s, path, _goal_xy(s), f"{EXECUTABLE}.interrupted{suffix}"), NODE, patience=2 * WAIT_WINDOW)


def goal_run(s: Session, action: Any, path: Any) -> None:
    """waits, goal_sent, logs_feedback, logs_result, ends."""
    xy = _goal_xy(s)
    distances = sorted((round(s.random.uniform(0.05, 0.95), 3) for _ in range(4)), reverse=True) + [0.0]
    # x at least 2 mm off the goal's: the record of the goal sent (x, y) never holds the final position
    final = (round(xy[0] + s.random.choice((-1, 1)) * s.random.uniform(0.002, 0.004), 3),
             round(xy[1] + s.random.uniform(-0.004, 0.004), 3))
    server = act.stand_in_action_server(s, action, ACTION, lambda index, goal: _result_script(
        action, final, distances, act.SUCCEEDED))
    rosout = s.graph.rosout()
    node = kit.start_node(s, "node_name", path, NODE, args=_params(xy), label=EXECUTABLE)
    if services.says_it_waits(s, "waits", rosout, node, ACTION, timeout=WAIT_WINDOW, what="action server"):
        services.waits_throttled(s, "waits_throttled", rosout, node, node_name=NODE, window=THROTTLE_WINDOW,
                                 period=WAIT_PERIOD)
    server.offer()
    with s.phase("observe"):
        kit.wait_until(lambda: bool(server.goals), LOG_TIMEOUT, abort=node.ended)
    expected = f"one goal, desired_position ({xy[0]}, {xy[1]}) (the parameters x and y)"
    if not server.goals:
        s.record("goal_sent", False, f"no goal in {LOG_TIMEOUT:.0f} s after the server appeared; "
                 f"last log records: {_last(rosout, node.proc)}; {kit.process_state(node.proc)}", expected)
        s.require("goal_sent")
    with s.phase("observe"):
        kit.wait_until(lambda: bool(server.ended), len(distances) * PERIOD + 2.0, abort=node.ended)
        kit.wait_until(lambda: any(_has(text, final[0]) and _has(text, final[1]) for text in _records(rosout, node.proc)),
                       LOG_TIMEOUT, abort=_gone(node.proc))
    records = _records(rosout, node.proc)
    found = _feedback_records(records, distances, final)
    anywhere = [d for d in distances if any(_has(text, d) for text in records)]
    s.record("logs_feedback", len(found) == len(distances),
             f"{len(found)} of the {len(distances)} distances sent ({', '.join(f'{d:.3f}' for d in distances)}) "
             "found in the log, each in a record of its own, in the order sent, before the result"
             + ("" if len(anywhere) == len(found) else
                f" ({len(anywhere)} written somewhere: several in one record, out of order, or only with the result)")
             + ("" if found else f"; last log records: {_last(rosout, node.proc)}"),
             "each distance_to_goal in a log record of its own as it arrives (the logger, not print())",
             fraction=len(found) / len(distances))
    shown = [text for text in records if _has(text, final[0]) and _has(text, final[1])]
    said = [text for text in shown if names_status(text, act.SUCCEEDED)]
    expected = f"a log record with the final position ({final[0]}, {final[1]}) and SUCCEEDED (as a word)"
    if said:
        s.record("logs_result", True, f"'{said[0][:120]}'", expected)
    elif shown:
        s.record("logs_result", False, f"'{shown[0][:120]}': the position, but not the status", expected)
    else:
        s.record("logs_result", False, f"no record with ({final[0]}, {final[1]}); last log records: {_last(rosout, node.proc)}",
                 expected)
    _ends(s, "ends", node.proc, "once its goal had SUCCEEDED")
    # counted once the client has ended (or END_TIMEOUT after its goal ended), not when the first goal ended: a
    # client that starts over (main() called at import, then by the entry point) sends its second goal about a
    # second after the first ended, and counting earlier made that verdict a race (CI of 893e21c)
    sent = [(g.desired_position.x, g.desired_position.y) for _, g in server.goals]
    shown = ", ".join(f"({x:g}, {y:g})" for x, y in sent[:3]) + (", ..." if len(sent) > 3 else "")
    s.record("goal_sent", len(sent) == 1 and abs(sent[0][0] - xy[0]) < 1e-9 and abs(sent[0][1] - xy[1]) < 1e-9,
             f"{len(sent)} goal(s) by the time the client had ended (or {END_TIMEOUT:.0f} s after the first "
             f"goal had): {shown}", expected)


def _feedback_records(records: list[str], distances: list[float], final: tuple[float, float]) -> list[float]:
    """The distances logged as the feedback arrived: each in a record of its own (one record matches one
    distance), in the order sent, not in a record holding the final position (the result's: a client that
    logs the Point (x, y, z=0.0) would show the last distance, 0.0, there)."""
    found: list[float] = []
    for text in records:
        if len(found) == len(distances):
            break
        if _has(text, final[0]) and _has(text, final[1]):
            break  # the result is logged: the feedback came before it
        if _has(text, distances[len(found)]):
            found.append(distances[len(found)])
    return found


def _ends(s: Session, check_id: str, proc: kit.LearnerProcess, when: str) -> bool:
    """Record ``check_id``: ``proc`` ends by itself within :data:`END_TIMEOUT` s, exit code 0, no traceback."""
    with s.phase("observe"):
        kit.wait_until(lambda: proc.poll() is not None, END_TIMEOUT)
    expected = f"the process ends by itself within {END_TIMEOUT:.0f} s, exit code 0, no traceback"
    ended = proc.exit_state()
    if ended is None:
        return s.record(check_id, False, f"still running {END_TIMEOUT:.0f} s {when}", expected)
    traceback = "Traceback (most recent call last)" in proc.stderr() + proc.stdout()
    ok = ended.returncode == 0 and not traceback
    return s.record(check_id, ok, f"{when}, the process {ended.describe()}"
                    + (f" ({ended.last_line})" if ended.last_line and not ok else ""), expected)


def _started(s: Session, path: Any, xy: tuple[float, float], label: str) -> kit.LearnerProcess:
    """Start the client with goal ``xy`` (the server is offered once it has logged); it may end before the graph
    shows it."""
    return s.launch(path, label, _params(xy))


def aborted_run(s: Session, action: Any, path: Any) -> None:
    """logs_aborted, aborted_ends: the grader's server aborts the goal after two feedback messages."""
    ended_run(s, action, path, act.ABORTED, "logs_aborted", "aborted_ends")


def canceled_run(s: Session, action: Any, path: Any) -> None:
    """logs_canceled, canceled_ends: the grader cancels the goal after two feedback messages (the server sends the
    cancel request itself, :class:`ros2course.kit.actions.Script`), so it ends CANCELED."""
    ended_run(s, action, path, act.CANCELED, "logs_canceled", "canceled_ends")


def ended_run(s: Session, action: Any, path: Any, status: int, check_id: str, ends_id: str | None = None) -> None:
    """Record ``check_id``: a goal the grader's server ends with ``status`` (ABORTED or CANCELED) after two
    feedback messages is logged with that status's name and the final position (half the goal); and
    ``ends_id`` (when given): the client then ends by itself.

    Raises:
        Unmet: no goal reached the server.
    """
    name = act.status_name(status)
    xy = _goal_xy(s)
    final = (round(xy[0] / 2, 3), round(xy[1] / 2, 3))
    server = act.stand_in_action_server(s, action, ACTION, lambda index, goal: _result_script(
        action, final, [0.6, 0.5], status))
    rosout = s.graph.rosout()
    proc = _started(s, path, xy, f"{EXECUTABLE}.{name.lower()}")
    act.offer_once_it_waits(s, server, rosout, NODE, proc, WAIT_WINDOW)
    with s.phase("observe"):
        kit.wait_until(lambda: any(names_status(text, status) for text in _records(rosout, proc)),
                       2 * LOG_TIMEOUT, abort=_gone(proc))
    with s.phase("observe"):  # the position may be in a record of its own, just after
        kit.wait_until(lambda: any(_has(text, final[0]) and _has(text, final[1]) for text in _records(rosout, proc)),
                       LOG_TIMEOUT, abort=_gone(proc))
    said = [text for text in _records(rosout, proc) if names_status(text, status)]
    where = [text for text in _records(rosout, proc) if _has(text, final[0]) and _has(text, final[1])]
    expected = f"a log record naming the status {name}, and the final position ({final[0]}, {final[1]})"
    if not server.goals:
        raise Unmet(f"no goal reached the server; last log records: {_last(rosout, proc)}; {kit.process_state(proc)}")
    ended = act.status_name(server.ended[0][1]) if server.ended else "not ended yet"
    s.record(check_id, bool(said and where),
             (f"'{said[0][:120]}'" + ("" if said[0] in where else f"; '{where[0][:120]}'" if where else
                                     f": no record with the final position ({final[0]}, {final[1]})"))
             if said else f"the goal ended {ended}; its log: {_last(rosout, proc)}", expected)
    if ends_id is not None:
        _ends(s, ends_id, proc, f"once its goal was {name}")


def rejected_run(s: Session, action: Any, path: Any) -> None:
    """handles_rejection: the grader's server rejects the goal."""
    xy = _goal_xy(s)
    server = act.stand_in_action_server(s, action, ACTION, lambda index, goal: act.Script(accept=False))
    rosout = s.graph.rosout()
    proc = _started(s, path, xy, f"{EXECUTABLE}.rejected")
    act.offer_once_it_waits(s, server, rosout, NODE, proc, WAIT_WINDOW)
    with s.phase("observe"):
        kit.wait_until(lambda: bool(server.goals), 2 * LOG_TIMEOUT, abort=lambda: proc.poll() is not None)
        if not server.goals:
            raise Unmet(f"no goal reached the server; last log records: {_last(rosout, proc)}; {kit.process_state(proc)}")
        kit.wait_until(lambda: any(re.search(r"reject", text, re.IGNORECASE) for text in _records(rosout, proc))
                       and proc.poll() is not None, END_TIMEOUT, abort=_gone(proc))
        if proc.poll() is not None:  # what it logged just before exiting may still be on its way
            kit.wait_until(lambda: False, 0.5)
    records = _records(rosout, proc)
    said = [text for text in records if re.search(r"reject", text, re.IGNORECASE)]
    after = records[records.index(said[0]) + 1:] if said else []
    pretends = [text for text in after if (PRETENDS.search(text) or ACCEPTED.search(text))
                and not re.search(r"reject", text, re.IGNORECASE)]
    ended = proc.exit_state()
    traceback = "Traceback (most recent call last)" in proc.stderr() + proc.stdout()
    problems = []
    if not said:
        problems.append(f"no log record says the goal was rejected (last records: {_last(rosout, proc)})")
    if ended is None:
        problems.append(f"still running {END_TIMEOUT:.0f} s after the rejection")
    elif ended.returncode != 0 or traceback:
        problems.append(f"the process {ended.describe()}" + (f" ({ended.last_line})" if ended.last_line else ""))
    if pretends:
        problems.append(f"after the rejection, a record that pretends the goal was accepted or ended: "
                        f"'{pretends[0][:120]}' (a rejected goal has no result: return before asking for it)")
    s.record("handles_rejection", not problems, "; ".join(problems) or f"'{said[0][:120]}', then the process "
             f"{ended.describe()}", "a log record saying the goal was rejected, no status or result logged after it, then exit code 0, "
             "no traceback")
