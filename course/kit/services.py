"""Kit steps that judge a learner's service server and client, the grader playing the other side (seed ch. 20-21).

Three lessons use it (issue 38's placement rule: a step two lessons use lives in the kit):
service-server-client (both halves), lifecycle-node (the transition services are asked with :func:`ask`)
and actions-client (:func:`says_it_waits`, for the action server).

A server is asked as ``ros2 service call`` asks it (:func:`ask`), its answers
judged case by case (:func:`answers`). For a client, the grader's
:class:`~ros2course.kit.topics_services.DeferredServer` (made with
:func:`~ros2course.kit.topics_services.stand_in_server` before the client
starts) stays out of the graph first: :func:`says_it_waits` looks for the client's
"waiting" log record. Once offered, it answers with points the client's log
must show (:func:`point_answers`, :func:`logs_answers`), its requests' send
stamps give the call rate (:func:`calls`), and answers sent late show whether
the client's executor stays free (:func:`keeps_calling`). Each step records
its own check(s); rates are judged on the requests' send stamps, never on
arrival times.
"""

from __future__ import annotations

import random
import re
import time
from collections.abc import Callable
from typing import Any

from ros2course.kit import LATE_DELIVERY, Session, call_service, wait_until
from ros2course.kit.judge import RATE_TOLERANCE, rate
from ros2course.kit.nodes import StartedNode, process_state
from ros2course.kit.topics_services import DeferredServer, has_point

#: A log record saying the client waits for the service (seed ch. 20.5: "service ... not available, waiting...").
WAITING = re.compile(r"wait|availab", re.IGNORECASE)
#: A log record saying the client gave up on a late answer (the seed's client: "Service Future
#: canceled. The Node took too long to process the service call...").
CANCELLED = re.compile(r"cancel|too long|took more than|timed? ?out", re.IGNORECASE)


def point_answers(rng: random.Random | None = None) -> Callable[[int, Any, Any], Any]:
    """A :class:`DeferredServer` handler filling ``response.point`` with points easy to find in a log.

    Each call gets another point, built from three random bases (100-899) and
    quarter steps, exact in binary and short in decimal, so any print format
    shows them (:func:`~ros2course.kit.topics_services.has_point` finds them rounded to 2 decimals).
    """
    rng = rng or random.Random()
    base = [rng.randrange(100, 900) for _ in range(3)]

    def answer(index: int, request: Any, response: Any) -> Any:
        response.point.x = base[0] + index + 0.25
        response.point.y = -(base[1] + index + 0.5)
        response.point.z = base[2] + 0.75 * ((index % 3) + 1)
        return response

    return answer


def says_it_waits(s: Session, check_id: str, rosout: Any, node: StartedNode, service: str,
                  timeout: float = 3.0, what: str = "service") -> bool:
    """Record ``check_id``: within ``timeout`` s, with ``service`` missing, the client logs that it waits.

    Args:
        rosout: the client's graph's :class:`~ros2course.run.probes.RosoutProbe` (made before it started).
        what: what is missing, for the feedback: ``"service"``, ``"action server"``.
    """
    def said() -> list:
        return rosout.records(match=lambda text: WAITING.search(text) is not None)

    with s.phase("observe"):
        wait_until(lambda: bool(said()), timeout, abort=node.ended)
    found = said()
    if found:
        return s.record(check_id, True, f"logged '{found[0].msg.strip()}' while {service} did not exist",
                        f"a log record saying it waits for the {what}")
    shown = " | ".join(r.msg.strip()[:80] for r in rosout.records()[:3]) or "no log records"
    return s.record(check_id, False, f"in {timeout:.0f} s without the {what}: {shown}; {process_state(node.proc)}",
                    f"a log record (e.g. '{what} {service} not available, waiting...') while the {what} is missing")


def waits_throttled(s: Session, check_id: str, rosout: Any, node: StartedNode, *, node_name: str,
                    window: float, period: float = 1.0) -> bool:
    """Record ``check_id``, right after :func:`says_it_waits` passed: with what the client waits for still
    missing ``window`` seconds more, its "waiting" records (their own stamps) come at most once every
    ``period`` seconds (the lessons' ``throttle_duration_sec=1.0``); one or two more than
    ``window / period + 1`` are forgiven (a timer that catches up after a late tick).

    ``node_name``: the client's node (records under another logger name are counted when it has none).
    """
    def waiting(name: str | None) -> list[float]:
        return sorted(r.stamp.sec + r.stamp.nanosec * 1e-9 for r in rosout.records(
            node=name, match=lambda text: WAITING.search(text) is not None))

    with s.phase("observe"):
        wait_until(lambda: False, window, abort=node.ended)
    stamps = waiting(node_name) or waiting(None)
    span = stamps[-1] - stamps[0] if stamps else 0.0
    allowed = int(span / period) + 2
    gaps = [b - a for a, b in zip(stamps, stamps[1:])]
    return s.record(check_id, len(stamps) <= allowed,
                    f"{len(stamps)} 'waiting' record(s) in {span:.1f} s while it waited"
                    + (f", {min(gaps):.2f} s apart at the closest" if gaps else ""),
                    f"at most one every {period:.0f} s (at most {allowed} in {span:.1f} s; "
                    "throttle_duration_sec=1.0)")


def calls(s: Session, calls_id: str, rate_id: str, server: DeferredServer, node: StartedNode, *,
          service: str, count: int, period: float) -> None:
    """Right after :meth:`DeferredServer.offer`: record ``calls_id`` (the client calls) and ``rate_id``.

    Waits for ``count`` calls (``count * period`` + 2 s, plus ``LATE_DELIVERY``
    while calls are missing); the rate is :func:`~ros2course.kit.judge.rate` over
    the requests' send stamps, one call every ``period`` seconds.

    Raises:
        Unmet: no call came (``s.require(calls_id)``).
    """
    offered = time.monotonic()
    patience = count * period + 2.0 + LATE_DELIVERY
    with s.phase("observe"):
        wait_until(lambda: len(server.calls) >= count, patience, abort=node.ended)
    got = server.calls_since(offered)
    expected = f"calls to {service} within {patience:.0f} s of it appearing"
    if not got:
        s.record(calls_id, False, f"no call in {time.monotonic() - offered:.1f} s; {process_state(node.proc)}",
                 expected)
        s.require(calls_id)
    s.record(calls_id, True, f"{len(got)} call(s), the first {got[0][0] - offered:.2f} s after the service "
             "appeared", expected)
    rate(s, rate_id, server.send_stamps(offered, count), period=period, needed=count,
         waited=time.monotonic() - offered, noun="call", source="the requests' send stamps",
         few_note=f"; {process_state(node.proc)}")


def _points(points: list[tuple[float, float, float]]) -> str:
    return ", ".join(f"({x:g}, {y:g}, {z:g})" for x, y, z in points)


def logs_answers(s: Session, check_id: str, server: DeferredServer, rosout: Any, node: StartedNode) -> bool:
    """Record ``check_id``: every point answered so far shows up in the client's log records.

    Waits 1 s for the last answer's record (plus ``LATE_DELIVERY`` while
    records are missing). A client that cancels a call still unanswered at
    its next tick (the seed's client does, and logs it) never logs an answer
    that reached it late on a loaded machine: each such cancel it logged
    excuses one missing point. Partial credit per point found.
    """
    sent = [(r.point.x, r.point.y, r.point.z) for _, r in server.answers]

    def logged(point: tuple[float, float, float]) -> bool:
        return any(has_point(rec.msg, point) for rec in rosout.records())

    def cancels() -> list:
        return rosout.records(match=lambda text: CANCELLED.search(text) is not None)

    with s.phase("observe"):
        wait_until(lambda: sum(not logged(p) for p in sent) <= len(cancels()), 1.0 + LATE_DELIVERY,
                   abort=node.ended)
    found = [p for p in sent if logged(p)]
    missing = [p for p in sent if p not in found]
    cancelled = cancels()
    excused = min(len(missing), len(cancelled))
    expected = ("each returned point in a log record (the logger, not print()); an answer the client "
                "cancelled as late, and said so in its log, may be missing")
    if found and len(missing) == excused:
        line = next(" ".join(x.strip() for x in r.msg.strip().splitlines() if x.strip())[:100]
                    for r in rosout.records() if has_point(r.msg, found[0]))
        late = (f"; {excused} answer(s) came late and the client cancelled them "
                f"('{cancelled[0].msg.strip()[:80]}')" if excused else "")
        return s.record(check_id, True, f"{len(found)} of the {len(sent)} points sent were logged, e.g. "
                        f"'{line}'{late}", expected)
    recent = " | ".join(r.msg.strip().replace("\n", " ")[:80] for r in rosout.records()[-2:]) or "none"
    shown = _points(sent[:3]) + (", ..." if len(sent) > 3 else "")
    return s.record(check_id, False, f"{len(found)} of the {len(sent)} points sent ({shown}) found in the log; "
                    f"missing e.g. {_points((missing or [(0.0, 0.0, 0.0)])[:1])}; last records: {recent}",
                    expected, fraction=len(found) / len(sent) if sent else 0.0)


def keeps_calling(s: Session, check_id: str, server: DeferredServer, node: StartedNode, *,
                  count: int, period: float, late: float) -> bool:
    """Answer ``late`` seconds late from now on; record ``check_id``: calls still come every ``period`` s.

    A client that keeps its executor free (``call_async`` + a done callback)
    goes on calling at its timer's rate; one that blocks on the answer
    (``spin_until_future_complete``, a busy wait, the synchronous ``call()``)
    calls at most once per ``late`` seconds. ``count`` calls (``count - 1``
    intervals), ±:data:`~ros2course.kit.judge.RATE_TOLERANCE`, on send stamps.
    """
    server.delay = late
    begin = time.monotonic()
    with s.phase("observe"):
        wait_until(lambda: len(server.calls_since(begin)) >= count, count * period + 1.0 + LATE_DELIVERY,
                   abort=node.ended)
    stats = server.rate(begin, count)
    expected = (f"calls keep coming every {period:.1f} s (± {RATE_TOLERANCE:.0%}, over {count - 1} intervals) "
                f"while each answer takes {late:.1f} s")
    if stats is not None and stats.samples >= count - 1 and stats.within(1.0 / period, RATE_TOLERANCE):
        return s.record(check_id, True, f"answers {late:.1f} s late: {stats.describe()}", expected)
    what = stats.describe() if stats else f"{len(server.calls_since(begin))} call(s)"
    return s.record(check_id, False, f"with answers {late:.1f} s late: {what} in {time.monotonic() - begin:.1f} s; "
                    "the client seems to wait for each answer before calling again (a blocked executor?); "
                    + process_state(node.proc), expected)


def answers(s: Session, check_id: str, ask: Callable[[Any], tuple[bool, str]], cases: list,
            expected: str, where: str = "") -> bool:
    """Record ``check_id`` on ``ask(case)`` -> ``(answer as expected, description)`` for each case.

    For a learner's service *server*, the grader being its client: partial
    credit per case answered as expected; observed lists every answer
    (``where`` appended, e.g. the name a misnamed service was called at).
    """
    results = [ask(case) for case in cases]
    passed = sum(ok for ok, _ in results)
    return s.record(check_id, passed == len(results), "; ".join(text for _, text in results) + where, expected,
                    fraction=passed / len(results))


def ask(s: Session, srv_type: type, service: str, request: Any, node: StartedNode,
        timeout: float = 3.0) -> tuple[Any, str]:
    """Call ``service`` once from the session's graph (``ros2 service call``): ``(response, "")``, or ``(None, why)``.

    ``why`` says the call was not made (the server's process ended) or got no
    answer within ``timeout`` seconds, with the process's state.
    """
    if node.ended():
        return None, f"not asked, {process_state(node.proc)}"
    try:
        return call_service(s.ros, srv_type, service, request, timeout=timeout), ""
    except TimeoutError as exc:
        return None, f"{exc}; {process_state(node.proc)}"


def quote_to_point(s: Session, srv_type: type, service: str, node: StartedNode, *, total: float,
                   tolerance: float, repeats: int = 1) -> Callable[[tuple[str, str, bool, int]], tuple[bool, str]]:
    """An ``ask`` for :func:`answers` on a service that takes a quote and returns a point (seed ch. 20's
    ``WhatIsThePoint``: ``request.quote.{id, quote, philosopher_name}``, ``response.point.{x, y, z}``).

    A case is ``(quote, philosopher, should the coordinates sum to total, quote id)``; it is answered as
    expected when ``|x + y + z - total| <= tolerance`` is what the case says, in each of ``repeats`` calls:
    the seed's server draws x and y at random, so one call can hide a rule that holds only for some draws
    (``z = 42 % (x + y)`` sums to 42 whenever 21 < x + y < 42). Observed shows the first answer that was
    wrong, else the first answer.
    """
    def once(case: tuple[str, str, bool, int]) -> tuple[bool, str]:
        text, philosopher, hits, quote_id = case
        request = srv_type.Request()
        request.quote.id, request.quote.quote, request.quote.philosopher_name = quote_id, text, philosopher
        response, why = ask(s, srv_type, service, request, node)
        if response is None:
            return False, f"'{text}' -- {philosopher}: {why}"
        point = response.point
        got = point.x + point.y + point.z
        return (abs(got - total) <= tolerance) == hits, (
            f"'{text}' -- {philosopher}: point ({point.x:.6g}, {point.y:.6g}, {point.z:.6g}), sum {got:.9g}")

    def call(case: tuple[str, str, bool, int]) -> tuple[bool, str]:
        answers = []
        for _ in range(repeats):
            answers.append(once(case))
            if not answers[-1][0]:
                break
        ok, text = answers[-1] if not answers[-1][0] else answers[0]
        if repeats > 1:
            text += f" (call {len(answers)} of {repeats})" if not ok else f" (and {repeats - 1} more calls alike)"
        return ok, text

    return call
