"""Grader for ``inspect-topics`` (tutorial ch. 19; contract in shared/LESSONS.md).

The grader's mystery node publishes one random AmazingQuote (random id, quote
and philosopher) on a random ``/amazing_quote_NNNN`` topic, through a random
number (1-3) of publishers, and listens on ``/amazing_quote_in``. Then it runs
the learner's ``cli/inspect_topics.sh`` in that graph (kit.scripts) and judges
what it printed (the random values only the real commands can show) and what
it published (the message the grader's subscription received).
A second run, in a fresh graph with no ``ros2`` daemon, starts another mystery
node only 3 s after the script's first ``ros2`` command joined the graph
(kit.scripts.run_script_first): a script that asks again until the topic shows
up finds it, one that looks once does not.
"""

from __future__ import annotations

from ros2course.kit import wait_until
from ros2course.kit import Check, Session, scripts
from ros2course.kit.mystery import INBOX_TOPIC, QuotePublisher, quote_inbox
from ros2course.kit.quotes import amazing_quote

SCRIPT = "cli/inspect_topics.sh"
TYPE = "package_with_interfaces/msg/AmazingQuote"
#: Seconds the script may run: each `ros2` command takes ~1 s to start; a command
#: without --once never ends and is stopped here (kept short: that fixture waits it out).
TIMEOUT = 25.0
#: The message the learner publishes (tutorial ch. 19.10).
PUB_ID = 1994
PUB_PHILOSOPHER = "Lloyd"
PUB_COMMAND = (f"ros2 topic pub --once {INBOX_TOPIC} {TYPE} "
               f"\"{{id: {PUB_ID}, quote: So you are telling me there is a chance, philosopher_name: {PUB_PHILOSOPHER}}}\"")

FIND_HINT = ("`ros2 topic list | grep quote` prints it; a list of only /parameter_events and /rosout comes from a "
             "daemon that has not discovered the node yet: `ros2 daemon start`, then ask again until the topic shows up")

LATE_HINT = ("a node you look for may join after your first look (a daemon that has just started has not "
             "discovered it yet): `ros2 daemon start`, then ask again, e.g. up to 10 times with `sleep 1` in between, "
             "until `ros2 topic list` shows the topic (the starter's loop)")

SCRIPTED = ("script",)
CHECKS = [
    Check("build", "package_with_interfaces builds with colcon", 1),
    Check("script", f"{SCRIPT} exists and is valid bash", 1),
    Check("ends", "The script ends by itself, with exit code 0", 2,
          "`ros2 topic echo` and `ros2 topic pub` run until Ctrl+C unless you add `--once`", needs=SCRIPTED),
    Check("topic_found", "It prints the name of the topic with 'quote' in it", 1, FIND_HINT, needs=SCRIPTED),
    Check("info", "It prints the topic's type and publisher count (ros2 topic info)", 2,
          "ros2 topic info <the topic>", needs=SCRIPTED),
    Check("echo", "It prints one message of the topic (ros2 topic echo --once)", 2,
          "ros2 topic echo --once <the topic>", needs=SCRIPTED),
    Check("published", f"It publishes an AmazingQuote with id {PUB_ID} and philosopher_name {PUB_PHILOSOPHER} "
          f"on {INBOX_TOPIC}", 2, PUB_COMMAND, needs=SCRIPTED),
    Check("asks_again", "It still finds the topic when its node joins only after the script's first look (as "
          "long after its first ros2 command as its first run took, 3 to 10 s), asking again until the topic shows "
          "up", 1, LATE_HINT, needs=("topic_found",)),
]


def grade(s: Session) -> None:
    msg_type = amazing_quote(s)
    path = scripts.script(s, "script", SCRIPT)
    mystery = QuotePublisher(s, msg_type)
    inbox = quote_inbox(s, msg_type)
    # a daemon that already lists the mystery topic, as in a learner's terminal (kit.scripts.ros2_daemon)
    run = scripts.run_script(s, path, timeout=TIMEOUT, daemon_sees=[mystery.topic])
    scripts.ended(s, "ends", run, "it ends by itself with exit code 0 (every `echo` and `pub` with `--once`)")
    if not scripts.printed(s, "topic_found", run, [mystery.topic], "name of the topic with 'quote' in it",
                           "ros2 topic list | grep quote"):
        s.amend("topic_found", hint=FIND_HINT)
    scripts.printed(s, "info", run, [f"Type: {TYPE}", f"Publisher count: {mystery.publishers}"],
                    f"type and publisher count of {mystery.topic}", f"ros2 topic info {mystery.topic}")
    scripts.printed(s, "echo", run, [f"id: {mystery.quote_id}", mystery.quote, mystery.philosopher],
                    f"message from {mystery.topic}", f"ros2 topic echo --once {mystery.topic}")
    # the second run goes on to its pub only where the first one's may have been lost: it ended by itself
    again = judge_late_topic(s, path, msg_type, scripts.late_by(run), inbox if run.returncode == 0 and not
                             run.timed_out else None)
    judge_inbox(s, inbox, again)


def _wanted(msg) -> bool:
    return msg.id == PUB_ID and msg.philosopher_name == PUB_PHILOSOPHER


def judge_late_topic(s: Session, path, msg_type, delay: float, first_inbox):
    """Record ``asks_again``: run the script again in a fresh graph with no daemon; the mystery node starts
    ``delay`` s (``kit.scripts.late_by``: as long as the first run took) after the script's first ``ros2``
    command joined the graph; its topic must be printed. The run stops once it has, unless ``first_inbox`` (the
    first run's, None: do not wait) missed the quote: then it goes on to its ``pub``. Returns this run's inbox
    (None when not run)."""
    if (blocker := s.unmet_need("asks_again")) is not None:
        s.record("asks_again", False, blocker, "")
        return None
    with s.part("late topic", own_graph=True):
        inbox = quote_inbox(s, msg_type)  # so that `ros2 topic pub --once` ends as in the first run
        late: list[QuotePublisher] = []
        run = scripts.run_script_first(s, path, lambda: late.append(QuotePublisher(s, msg_type)),
                                       late_by=delay, timeout=TIMEOUT,
                                       until=lambda out: bool(late) and late[0].topic in out and (
                                           first_inbox is None or any(_wanted(m) for m in
                                                                      first_inbox.messages() + inbox.messages())))
        found = late[0].topic in run.run.stdout
        s.record("asks_again", found,
                 f"{run.describe()}; " + (f"it printed {late[0].topic}" if found else
                                          f"it never printed {late[0].topic}; it printed: "
                                          f"{scripts.excerpt(run.run.stdout)}"),
                 f"the script finds and prints the topic of a node that joins {delay:.1f} s after its first "
                 "ros2 command, as long as its first run took (it asks again until the topic shows up)")
    return inbox


def judge_inbox(s: Session, inbox, again=None) -> None:
    """Record ``published``: the grader's subscription on /amazing_quote_in received id 1994 from Lloyd, in the
    script's first run or in its second (``again``: the late-topic run's inbox, None when it did not run).

    ``ros2 topic pub --once`` publishes as soon as it sees the grader's subscription and is gone 0.1 s later
    (its ``--keep-alive``); when the grader's side has not matched its publisher yet, the reliable sample is
    dropped and never repaired (1 reference run in 20 at load 2, stop 72), so the same script's second run
    counts too: what it sends is the same."""
    wait_until(lambda: any(_wanted(m) for m in inbox.messages()), 2.0)  # a reliable sample in flight
    received = inbox.messages() or (again.messages() if again is not None else [])
    expected = f"the grader receives id {PUB_ID}, philosopher_name {PUB_PHILOSOPHER} on {INBOX_TOPIC}"
    if any(_wanted(m) for m in received):
        s.record("published", True, f"the grader received {len(received)} message(s) on {INBOX_TOPIC}, "
                 f"id {PUB_ID} from {PUB_PHILOSOPHER} among them", expected)
    elif received:
        seen = ", ".join(f"(id {m.id}, philosopher_name {m.philosopher_name!r})" for m in received[:3])
        s.record("published", False, f"the grader received {seen} on {INBOX_TOPIC}", expected,
                 hint=f"set the values in the YAML text: {PUB_COMMAND}")
    else:
        s.record("published", False, f"the grader received nothing on {INBOX_TOPIC}", expected)
