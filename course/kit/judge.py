"""Kit judgements over what was observed: rates on send stamps, the graph's topics."""

from __future__ import annotations

from typing import Any

from ros2course.kit.session_protocol import Session
from ros2course.run.probes import RateStats

#: Tolerance on a mean period, as a fraction (shared/LESSONS.md: rates within ±15 %).
RATE_TOLERANCE = 0.15
#: Endpoints every rclpy node has; not the learner's doing, left out of "observed" lists.
STANDARD_TOPICS = frozenset({"/rosout", "/parameter_events"})


def rate(s: Session, check_id: str, times: list[float], *, period: float, needed: int = 0,
         waited: float = 0.0, noun: str, source: str, where: str = "", few_note: str = "",
         span: float | None = None, expected_note: str = "", sequence: list[int | None] | None = None,
         median: bool = False) -> bool:
    """Record ``check_id`` on the mean period of ``times`` (seconds, oldest first).

    The one rate judgement of the kit. The formula is ``ros2 topic hz``'s
    (1 / mean delta, ros2topic/verb/hz.py), over stamps taken where the event
    happened (a message's DDS send stamp, a /rosout record's stamp, a request's
    send stamp), never over arrival times: a loaded machine handing the grader
    two messages at once must not change the verdict.

    Args:
        period: expected seconds between events; ±:data:`RATE_TOLERANCE` on the mean.
        needed: events needed (``needed - 1`` intervals, at least 5 per shared/LESSONS.md).
        waited: seconds the grader waited, shown when too few events came.
        noun: what an event is, for the learner ("message", "record", "call").
        source: what ``times`` are, e.g. "the messages' send stamps".
        where: appended to the observed text (e.g. the topic the node really uses, or what
            ``ros2 topic hz`` over arrival times would show).
        few_note: appended only when too few events came (e.g. the process state).
        span: instead of ``needed``: the events must cover at least 90 % of ``span``
            seconds (fast streams, e.g. sas's 500 Hz joint states, where a count says
            less than the time covered).
        expected_note: appended to the expected text.
        sequence: each event's publication sequence number, when the reader has them: messages
            the grader's reader missed then count as intervals of the publisher's
            (:meth:`RateStats.from_times`); ``ros2course evidence`` recomputes the rate from the
            recorded messages only.
        median: judge the median period instead of the mean: for a fast timer-driven stream (sas's
            500 Hz joint states), where a busy machine delays some callbacks and rcl's timer then skips
            the periods it missed (rcl/src/rcl/timer.c, ``rcl_timer_call``): the mean then says how
            busy the machine was, the median which period the node asked for. The mean is shown beside it.
    """
    stats = RateStats.from_times(times, sequence)
    # the span judged, for the check's recording (``ros2course evidence`` recomputes the rate from it)
    window = (min(times), max(times)) if times else None
    band = (period * (1 - RATE_TOLERANCE), period * (1 + RATE_TOLERANCE))  # the mean (median) period allowed, seconds
    shown = f"{period * 1000:.{1 if period < 0.01 else 0}f} ms" if period < 0.1 else f"{period:.3f} s"
    over = f"over at least {span:.1f} s of {noun}s" if span else f"over at least {needed - 1} intervals"
    statistic = "median" if median else "mean"
    expected = f"{1.0 / period:.2f} Hz: {statistic} period {shown} ± {RATE_TOLERANCE:.0%}, {over}{expected_note}"
    covered = window[1] - window[0] if window else 0.0
    if stats is None or (covered < span * 0.9 if span else stats.samples < needed - 1):
        within = f"over {covered:.2f} s" if span else f"within {waited:.1f} s"
        return s.record(check_id, False, f"only {len(times)} {noun}(s) {within}"
                        + (f" ({stats.describe()})" if stats else "") + where + few_note, expected, window=window, band=band,
                        band_of=statistic)
    shown_median = (f"; median period {stats.median_period * 1000:.2f} ms" if stats.median_period < 0.1
                    else f"; median period {stats.median_period:.3f} s") if median else ""
    return s.record(check_id, stats.within(1.0 / period, RATE_TOLERANCE, median=median),
                    f"{stats.describe()}{shown_median} (from {source}){where}", expected, window=window,
                    band=band, band_of=statistic)


def topics_seen(graph: Any) -> str:
    """``/a (pkg/msg/T), /b (...)``: what ``ros2 topic list -t`` shows in ``graph``, ROS's own topics left out."""
    topics = {name: types for name, types in graph.topic_types().items() if name not in STANDARD_TOPICS}
    return ", ".join(f"{name} ({', '.join(types)})" for name, types in sorted(topics.items())) or "none"
