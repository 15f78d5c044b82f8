"""AmazingQuote observations: the quote publisher's contract, shared by the parameters, launch-files and
param-dump-load graders (seed ch. 22, 24), and a subscriber fed quotes (publisher-subscriber, seed ch. 19).

Contract names come from shared/LESSONS.md; the launch file's values from the
seed's ch. 22.9 listing.
"""

from __future__ import annotations

import os
import random
import time
from pathlib import Path
from typing import Any

from ros2course.grade.checklist import Unmet
from ros2course.kit.session_protocol import Session
from ros2course.run.probes import LATE_DELIVERY, wait_until
from ros2course.kit.judge import topics_seen
from ros2course.kit.launch import NodeAction, start_node_action
from ros2course.kit.nodes import process_state
from ros2course.kit.packages import source_package
from ros2course.kit.topics_services import has_integer, publisher

PACKAGE = "python_package_that_uses_parameters_and_launch_files"
EXECUTABLE = "amazing_quote_configurable_publisher_node"
NODE = "amazing_quote_configurable_publisher_node"
INTERFACES = "package_with_interfaces"

#: Parameters the node declares and their defaults (seed ch. 22.3).
DEFAULTS: dict[str, Any] = {
    "quote": "Use the force, Pikachu!",
    "philosopher_name": "Uncle Ben",
    "topic_name": "amazing_quote",
    "period": 0.5,
}

#: The launch file of seed ch. 22.9.
LAUNCH_FILE = "peanut_butter_falcon_quote_publisher_launch.py"
LAUNCH_NODE = "peanut_butter_falcon_quote_publisher_node"
LAUNCH_TOPIC = "truly_inspirational_quote"
LAUNCH_PERIOD = 0.25  # seconds
LAUNCH_PHILOSOPHER = "Tyler"
LAUNCH_QUOTE = ("Yeah, you're gonna die, it's a matter of time. That ain't the question. The question's, "
                "whether they're gonna have a good story to tell about you when you're gone")
LAUNCH_PARAMETERS: dict[str, Any] = {
    "topic_name": LAUNCH_TOPIC,
    "period": LAUNCH_PERIOD,
    "quote": LAUNCH_QUOTE,
    "philosopher_name": LAUNCH_PHILOSOPHER,
}


def amazing_quote(s: Session) -> type:
    """The workspace's ``package_with_interfaces/msg/AmazingQuote`` class (NotGradable if not built)."""
    return s.interface_type(INTERFACES, "msg", "AmazingQuote")


def short(text: str, limit: int = 70) -> str:
    """``text`` quoted, cut to ``limit`` characters."""
    return repr(text if len(text) <= limit else text[:limit - 3] + "...")


def first_difference(got: str, wanted: str) -> str:
    """Where ``got`` first differs from ``wanted``, e.g. ``differs at character 73: '...question.The'``."""
    if got == wanted:
        return "identical"
    index = len(os.path.commonprefix([got, wanted]))
    start = max(0, index - 15)
    return (f"differs from character {index + 1}: got {got[start:index + 15]!r}, "
            f"expected {wanted[start:index + 15]!r}")


def package_source(s: Session) -> Path | None:
    """The learner's ``src/.../python_package_that_uses_parameters_and_launch_files`` folder, if any."""
    found = source_package(s, PACKAGE)
    return found[0] if found else None


def quote_after(s: Session, check_id: str, probe: Any, since: float, *, count: int, period: float,
                quote: str, philosopher: str, proc: Any, expected: str, prefix: str = "", stale: str = "") -> bool:
    """Record ``check_id`` on the ``count``-th AmazingQuote message sent after ``since`` (wall clock, ``time.time()``).

    A parameter change must show within ``count`` messages (one may already be
    on its way when it is made: seed ch. 24.5); judged on send stamps
    (``TopicProbe.wait_sent_after``: up to ``count * period`` s plus
    ``LATE_DELIVERY``). Half the credit each for ``quote`` and ``philosopher``.

    Args:
        probe: the :class:`~ros2course.run.probes.TopicProbe` of the quote topic.
        period: the publisher's period in seconds.
        proc: the publisher's process (the wait ends if it dies; its state is shown).
        prefix: opens the observed text (e.g. "set_parameters succeeded; ").
        stale: appended when a value did not change (a likely cause for the learner).
    """

    with s.phase("observe"):
        later = probe.wait_sent_after(since, count, period, abort=lambda: proc.poll() is not None)
    if not later:
        return s.record(check_id, False, f"{prefix}no message after the change; {process_state(proc)}", expected)
    last = later[min(count, len(later)) - 1]
    quote_ok, name_ok = last.quote == quote, last.philosopher_name == philosopher
    seen = ", ".join(f"({short(m.quote, 30)}, {m.philosopher_name!r})" for m in later[:count])
    return s.record(check_id, quote_ok and name_ok,
                    f"{prefix}the next {len(later[:count])} message(s) were {seen}"
                    + ("" if quote_ok and name_ok else stale), expected, fraction=(quote_ok + name_ok) / 2)


# --- a learner's subscriber, fed quotes the grader makes up (seed ch. 19) -----------------

_WORDS = ["teapot", "lantern", "cactus", "harbour", "violin", "comet", "pebble", "marmalade", "glacier",
          "walrus", "origami", "thunder", "velvet", "compass", "biscuit", "nebula"]
_NAMES = ["Ada", "Grace", "Alan", "Edsger", "Barbara", "Donald", "Margaret", "Linus", "Radia", "Ken"]


def made_up(msg_type: type, count: int, rng: random.Random | None = None) -> list:
    """``count`` AmazingQuote messages nobody hard-codes: random words, philosophers and ids (100000-999999),
    drawn from ``rng`` (a grader passes ``s.random``: other files, other quotes; the same files, the same)."""
    rng = rng or random.Random()
    out = []
    for _ in range(count):
        a, b, c = rng.sample(_WORDS, 3)
        out.append(msg_type(id=rng.randrange(100_000, 1_000_000), quote=f"A {a} in the {b} is worth two {c}s.",
                            philosopher_name=f"{rng.choice(_NAMES)} {rng.choice(_WORDS).capitalize()}"))
    return out


#: Share of the grader's quotes a subscriber must log after their first publication (the rest may need the
#: second chance: a message lost, or a record later than 1 s on a loaded machine). Logging every other message
#: gives about 1 in ``count``, logging the previous message none.
FIRST_SHARE = 0.75


def subscriber_logs(s: Session, quotes_id: str, details_id: str, node: Any, rosout: Any, topic: str,
                    msg_type: type, *, count: int, where: str = "", graph: Any = None) -> None:
    """Publish ``count`` :func:`made_up` quotes on ``topic``; record what the subscriber logged.

    Like ``ros2 topic pub``: the grader's publisher waits (3 s) until the
    subscriber is matched, then publishes each quote and waits up to 1 s for
    its text on /rosout, publishing it once more if it did not show.
    ``quotes_id``: each quote's text is in a record (partial credit; a note
    when the texts went to stdout: ``print()``), and at least :data:`FIRST_SHARE` of them after their first
    publication: a subscriber that logs every other message, or the one before, shows each quote only once
    it was published again (audit of stop 71). ``details_id``: the
    philosopher and the id of each logged quote are in the log too (any record).

    Args:
        node: the subscriber (:class:`~ros2course.kit.StartedNode`); rosout: its graph's /rosout probe.
        where: appended to observed texts (a misnamed topic the quotes went to).

    Raises:
        Unmet: no quote was logged (``details_id`` cannot be judged).
    """

    quotes = made_up(msg_type, count, s.random)

    def seen(msg: Any) -> bool:
        return any(msg.quote in r.msg for r in rosout.records())

    at_first = []  # the quotes logged after their first publication, not only after the second chance
    with publisher(s, topic, msg_type, graph) as pub, s.phase("observe"):
        wait_until(lambda: pub.get_subscription_count() > 0, 3.0, abort=node.ended)  # else the first is lost
        for msg in quotes:
            for attempt in range(2):  # a second chance if a message was lost
                pub.publish(msg)
                if wait_until(lambda m=msg: seen(m), 1.0, abort=node.ended):
                    at_first += [msg] if attempt == 0 else []
                    break
    records = rosout.records()
    logged = [m for m in quotes if any(m.quote in r.msg for r in records)]
    expected = (f"each quote's text in a log record of the subscriber (the grader's own quotes), at least "
                f"{FIRST_SHARE:.0%} of them logged when first published")
    if len(logged) == len(quotes) and len(at_first) < FIRST_SHARE * len(quotes):
        s.record(quotes_id, False, f"all {len(quotes)} quotes were logged, but only {len(at_first)} when first "
                 "published: the others only once the grader published them a second time (is every message "
                 "logged, and the message received, not an earlier one?)" + where, expected,
                 fraction=len(at_first) / len(quotes))
    elif len(logged) == len(quotes):
        s.record(quotes_id, True, f"all {len(quotes)} quotes published were logged, e.g. {quotes[0].quote!r}" + where,
                 expected)
    else:
        recent = " | ".join(r.msg.strip().replace("\n", " ")[:80] for r in records[-2:]) or "no log records"
        on_stdout = any(m.quote in node.proc.stdout() for m in quotes)
        s.record(quotes_id, False,
                 f"{len(logged)} of {len(quotes)} quotes found in the log (e.g. {quotes[0].quote!r} was published)"
                 f"{where}; last records: {recent}"
                 + ("; the quotes appeared on stdout only (print() instead of the logger?)" if on_stdout else "")
                 + f"; {process_state(node.proc)}", expected, fraction=len(logged) / len(quotes))
    if not logged:
        raise Unmet("no quote was logged")
    items = [(m, what, ok) for m in logged
             for what, ok in (("philosopher_name", any(m.philosopher_name in r.msg for r in records)),
                              ("id", any(has_integer(r.msg, m.id) for r in records)))]
    missing = [f"{what} of {m.quote!r} ({getattr(m, what)!r})" for m, what, ok in items if not ok]
    s.record(details_id, not missing, "philosopher and id of every logged quote found" if not missing
             else "missing: " + "; ".join(missing[:2]), "each quote's philosopher_name and id in the log too",
             fraction=(len(items) - len(missing)) / len(items))


# --- the configurable publisher, started and changed ---------------------------------------

def start_as_launched(s: Session, check_id: str, probe: Any) -> Any:
    """Start the publisher as the launch-files lesson's launch file starts it (:data:`LAUNCH_PARAMETERS`,
    node :data:`LAUNCH_NODE`, with :func:`ros2course.kit.launch.start_node_action`); record ``check_id``: the
    node appears (10 s) and its first message reaches ``probe`` (the /:data:`LAUNCH_TOPIC` TopicProbe).

    Returns:
        The process (stopped by the engine at the end of the check).

    Raises:
        Unmet: no executable, no node, or no message on the topic.
    """

    action = NodeAction(line=0, package=PACKAGE, executable=EXECUTABLE, name=LAUNCH_NODE,
                        parameters=[dict(LAUNCH_PARAMETERS)])
    expected = (f"node /{LAUNCH_NODE} publishing the launch file's quote on /{LAUNCH_TOPIC} "
                f"(started like the launch-files lesson's launch file)")
    proc, reason = start_node_action(s, action, f"{EXECUTABLE}.as_launched")
    if proc is None:
        s.record(check_id, False, reason, expected)
        raise Unmet("the node could not be started")
    with s.phase("start"):
        found = s.graph.wait_for_node(LAUNCH_NODE, 10.0, abort=lambda: proc.poll() is not None)
        if found:
            probe.wait_for_count(1, timeout=3.0 + LATE_DELIVERY, abort=lambda: proc.poll() is not None)
    samples = probe.samples()
    if not found or not samples:
        seen = ", ".join(s.graph.node_names()) or "none"
        s.record(check_id, False, (f"no message on /{LAUNCH_TOPIC}; topics seen: {topics_seen(s.graph)}"
                                   if found else f"no node {LAUNCH_NODE}; nodes seen: {seen}")
                 + f"; {process_state(proc)}", expected)
        raise Unmet("the node is not running as the launch file would run it")
    first = samples[0][1]
    s.record(check_id, True, f"/{LAUNCH_NODE} publishes quote {short(first.quote, 40)} "
             f"by {first.philosopher_name!r} on /{LAUNCH_TOPIC}", expected)
    return proc


def set_at_runtime(s: Session, check_id: str, services: Any, probe: Any, proc: Any, *, quote: str,
                   philosopher: str, count: int, period: float, topic: str) -> bool:
    """``ros2 param set`` quote and philosopher_name on the running publisher; record ``check_id``:
    the ``count``-th message sent afterwards carries them (:func:`quote_after`, on send stamps).

    Args:
        services: the node's :class:`~ros2course.kit.params.NodeParameters`.
        probe: the TopicProbe of ``topic``; proc: the publisher's process.
    """

    expected = (f"within {count} messages after the change, quote {short(quote)} "
                f"and philosopher_name {philosopher!r}")
    if not probe.samples():
        return s.record(check_id, False, f"no message on {topic} to compare with", expected)
    results = services.set({"quote": quote, "philosopher_name": philosopher})
    changed_at = time.time()  # the node applied the change before it answered: later send stamps are after it
    failed = [f"{r.name}: {r.reason or 'refused'}" for r in results if not r.successful]
    if failed:
        return s.record(check_id, False, "set_parameters failed: " + "; ".join(failed), expected)
    return quote_after(s, check_id, probe, changed_at, count=count, period=period, quote=quote,
                       philosopher=philosopher, proc=proc, expected=expected, prefix="set_parameters succeeded; ",
                       stale=" -- the node still publishes the old values: does it read the parameters only once?")


def id_counts(s: Session, check_id: str, messages: list, where: str = "") -> bool:
    """Record ``check_id``: the AmazingQuote ``id`` of ``messages`` (in arrival order) counts up by 1 from one
    message to the next (the publisher-subscriber lesson's counter, kept by the parameters lesson: "the id
    field counts up from 0, as before"). ``where``: appended to what was observed (e.g. the topic).

    Returns whether it passed; one message is not enough to tell (failed, saying so).
    """
    ids = [int(m.id) for m in messages]
    shown = ", ".join(map(str, ids))
    if len(ids) < 2:
        return s.record(check_id, False, f"only {len(ids)} message(s) (id {shown or 'none'}) to compare" + where,
                        "ids n, n+1, n+2, ...")
    return s.record(check_id, all(b - a == 1 for a, b in zip(ids, ids[1:])), f"ids {shown}" + where,
                    f"ids {ids[0]}, {ids[0] + 1}, {ids[0] + 2}, ... (each one more than the previous)")


#: Seconds a fresh instance of a quote publisher may take to send its first message (a Python node starts in about
#: 1 s; a loaded machine is slower).
FRESH_START_TIMEOUT = 10.0


def counts_from_zero(s: Session, check_id: str, messages: list, path: Path, topic: str, msg_type: type,
                     period: float, args: list[str] | None = None, where: str = "",
                     sequence: int | None = None) -> bool:
    """Record ``check_id``: the publisher's first AmazingQuote has ``id`` 0 (publisher-subscriber: "the id starts at
    0"; parameters: "the id field counts up from 0, as before").

    ``messages`` (in arrival order) came to a subscription made before the
    node started. A publisher is volatile, though: a message it sends before
    the subscription is matched is lost (ROS 2 QoS, durability), and whether
    discovery matched them before the node's first write is a race (a node
    that publishes at once, before spinning, loses its first message in some
    runs and not in others). So the first id heard is judged against the
    publication sequence number of that message (``sequence``: the writer's
    count, 1 for its first): a first message heard with number k was the
    node's k-th, and its counter started at 0 when its id is k - 1, whichever
    messages discovery lost. Only when the middleware gives no sequence
    number and the first id heard is not 0 is a fresh instance of ``path``
    (``args``: its ``--ros-args``), in a graph of its own with the grader's
    subscription made first, asked again (stopped at the end of the check).

    Args:
        messages: what the first run's subscription received, oldest first.
        path: the publisher's executable (from ``kit.executable``).
        topic: where the fresh instance publishes (e.g. ``/amazing_quote``).
        msg_type: the workspace's AmazingQuote class.
        period: the publisher's timer period, seconds.
        where: appended to what was observed (e.g. the topic).
        sequence: the publication sequence number of ``messages[0]``
            (:meth:`ros2course.run.probes.TopicProbe.sequence_numbers`), None when unknown.

    Returns whether it passed; no message in the first run is failed (nothing to tell).
    """
    expected = "ids 0, 1, 2, ...: the first message has id 0 (initialise the counter to 0, publish, then add 1)"
    if not messages:
        return s.record(check_id, False, "no message to read the first id from" + where, expected)
    first = int(messages[0].id)
    if first == 0:
        return s.record(check_id, True, f"the first message has id 0 (ids {_ids(messages)})" + where, expected)
    if sequence:
        start = first - (sequence - 1)
        lost = (f"; the {sequence - 1} sent before it were lost before this subscription matched the publisher"
                if sequence > 1 else "")
        return s.record(check_id, start == 0, f"the first message heard has id {first} (ids {_ids(messages)}) and was "
                        f"the publisher's message number {sequence}, so its first had id {start}{lost}{where}",
                        expected)
    graph = s.new_graph()
    probe = graph.topic(topic, msg_type)
    proc = s.launch(path, f"{path.name}.from-zero", args, graph=graph)
    with s.phase("observe"):
        probe.observe(2, period, FRESH_START_TIMEOUT, abort=lambda: proc.poll() is not None)
    again = probe.messages()
    second = f"ids {_ids(again)}" if again else f"no message on {topic} ({process_state(proc)})"
    ok = bool(again) and int(again[0].id) == 0
    return s.record(check_id, ok, f"the first message heard has id {first} (ids {_ids(messages)}){where}; a fresh "
                    f"instance, heard from its start, sent {second}", expected)


def _ids(messages: list, limit: int = 6) -> str:
    """The first ``limit`` ids of ``messages``, comma separated (``...`` when there are more)."""
    shown = ", ".join(str(int(m.id)) for m in messages[:limit])
    return shown + (", ..." if len(messages) > limit else "")


def texts(s: Session, check_id: str, messages: list, quote: str, philosopher: str, source: str) -> bool:
    """Record ``check_id``: every AmazingQuote in ``messages`` says ``quote`` by ``philosopher``.

    Observed names the first message that differs and where its quote first
    differs from ``quote`` (:func:`first_difference`: a missing space between
    glued string literals shows). ``source`` says where the quote comes from (e.g. "ch. 22.9").
    """
    wrong = [m for m in messages if m.quote != quote or m.philosopher_name != philosopher]
    expected = f"quote {short(quote)} ({source}), philosopher_name {philosopher!r}"
    if not wrong:
        return s.record(check_id, True, f"all {len(messages)} messages carry the quote and {philosopher!r}", expected)
    msg = wrong[0]
    parts = []
    if msg.quote != quote:
        parts.append(f"quote {short(msg.quote)} {first_difference(msg.quote, quote)}")
    if msg.philosopher_name != philosopher:
        parts.append(f"philosopher_name {msg.philosopher_name!r}")
    return s.record(check_id, False, f"{len(wrong)} of {len(messages)} messages differ: " + "; ".join(parts), expected)
