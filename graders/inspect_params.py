"""Grader for ``inspect-params`` (tutorial ch. 24; contract in shared/LESSONS.md).

The grader plays the launch-files lesson's node (``/peanut_butter_falcon_quote_publisher_node``,
the parameters lesson's interface, :class:`ros2course.kit.mystery.ConfigurableQuotePublisher`)
with a random initial ``quote``, runs the learner's ``cli/inspect_params.sh`` (a ``ros2`` daemon already listing the node)
in that graph and judges: the parameter names and the random quote in its
output, the quote the node publishes after the script's ``ros2 param set``
(messages sent after the node accepted the change, by send stamps), and the
file ``cli/params_dump.yaml`` (the ``ros2 param dump`` format). A second run, in
a fresh graph with no ``ros2`` daemon, starts the node only as long after the
script's first ``ros2`` command joined the graph as the first run took (3 to 10 s; kit.scripts.run_script_first),
beside another node listed from the start (:data:`OTHER_NODE`, as in a learner's terminal where more
than one node runs): a script that waits until ``ros2 node list`` shows *the* node still gets its
quote; one that asks at once, or stops waiting when any node is listed, does not. The first run also shows whether the
wait ends when the node shows: its first ``ros2 param`` command must come
soon after the script starts (the node is listed all along), not after the
whole loop of tries (a loop whose test never matches waits its 10 tries,
then asks whether the node came or not).
"""

from __future__ import annotations

import time
from typing import Any

import yaml

from ros2course.kit import Check, Session, params, scripts

from ._inspect_params import DumpPlaceholder, FirstParamCommand, get_lines, without_fastdds_log
from ros2course.kit.mystery import (
    CONFIGURABLE_NODE,
    CONFIGURABLE_PERIOD,
    CONFIGURABLE_TOPIC,
    ConfigurableQuotePublisher,
    MysteryNode,
)
from ros2course.kit.quotes import amazing_quote, short

SCRIPT = "cli/inspect_params.sh"
DUMP = "cli/params_dump.yaml"
NODE = f"/{CONFIGURABLE_NODE}"
#: Another node in the late run's graph from the start (the tutorial's demo talker's name): a wait that ends
#: when ``ros2 node list`` shows any node, not the one the script asks about, ends too soon (held-out seed 23
#: left ``grep -q ""`` alive while the late node was the only one to list).
OTHER_NODE = "talker"
#: The value the lesson names for ``ros2 param set`` (tutorial ch. 24.5, shortened).
NEW_QUOTE = "You got a good-guy heart. That's just who you are."
SET_COMMAND = f"ros2 param set {NODE} quote \"{NEW_QUOTE}\""
#: The parameters the node declares (ros2 param list prints each on a line, indented two spaces).
NAMES = ("period", "philosopher_name", "quote", "topic_name")
TIMEOUT = 60.0  # seconds for the whole script: each ros2 command starts in ~1 s, 3 s on a busy machine (a loop
# that waits all its 10 tries took over 30 s under CI's load of stop 73, and lost `ends` and `got` with it)
NEXT_MESSAGES = 2  # the change must show within this many messages (one may be on its way)

#: Seconds from the start of the first run (a daemon lists the node all along) by which the script's first
#: ``ros2 param`` command must have joined the graph. A script that checks once and breaks takes 2-5 s to get
#: there (``ros2 daemon start``, one ``ros2 node list``: about 1 s each, more on a busy machine); the
#: starter's loop whose test never matches takes its 10 tries, 10 pauses of 1 s and 10 ``ros2 node list``,
#: at least 15 s.
PROMPT = 12.0

WAIT_HINT = ("the node may join after your first command (a daemon that has just started has not discovered it "
             "yet): `ros2 daemon start`, then wait until `ros2 node list` shows the node (the starter's loop) "
             "before the first `ros2 param` command")

SCRIPTED = ("script",)
CHECKS = [
    Check("build", "package_with_interfaces builds with colcon", 1),
    Check("script", f"{SCRIPT} exists and is valid bash", 1),
    Check("ends", "The script ends by itself, with exit code 0", 1,
          "run it yourself: the first command that prints an error is the one to fix", needs=SCRIPTED),
    Check("listed", "It prints the node's parameter names (ros2 param list)", 1, f"ros2 param list {NODE}",
          needs=SCRIPTED),
    Check("got", "It prints the node's current quote (ros2 param get)", 2, f"ros2 param get {NODE} quote",
          needs=SCRIPTED),
    Check("set", "It sets quote to the lesson's text and the next messages carry it (ros2 param set)", 3,
          SET_COMMAND, needs=SCRIPTED),
    Check("dump_file", f"It writes {DUMP} in the ros2 param dump format, with every parameter of the node", 2,
          f"ros2 param dump {NODE} > {DUMP} (the whole output: it lists every parameter)", needs=SCRIPTED),
    Check("dump_after_set", "The dump holds the new quote (dumped after the set)", 1,
          "dump after the set, so the file saves the node's parameters as they are now", needs=("dump_file",)),
    Check("waits_for_node", "It waits for a node that joins only after the script's questions (as long after "
          "its first ros2 command as its first run took, 3 to 10 s; another node is listed from the start) before "
          "asking it (ros2 node list until it shows the node)", 1, WAIT_HINT, needs=("got",)),
]


def grade(s: Session) -> None:
    node = ConfigurableQuotePublisher(s, amazing_quote(s))
    path = scripts.script(s, "script", SCRIPT)
    dump = s.workspace_root / DUMP
    placeholder = DumpPlaceholder(dump)  # a file the script's `>` must replace: `>>` leaves it in (lesson: overwrites)
    s.on_close(placeholder.remove_if_left)  # whatever stops the grading: the learner's folder as it was
    started = time.time()
    # a daemon that already lists the node, as in a learner's terminal (kit.scripts.ros2_daemon); the second run
    # (judge_late_node) has none
    watch = FirstParamCommand(s.ros.node)
    try:
        run = scripts.run_script(s, path, timeout=TIMEOUT, daemon_sees=[NODE])
    finally:
        watch.stop()
    asked_at = watch.seconds_after(time.monotonic() - run.seconds)
    scripts.ended(s, "ends", run, "it ends by itself with exit code 0")
    scripts.printed(s, "listed", run, [f"  {name}" for name in NAMES],  # --param-type appends " (type: ...)"
                    f"the names of {NODE}'s parameters, one per line", f"ros2 param list {NODE}", whole_lines=True,
                    line_text=lambda line: line.rstrip().split(" (type: ")[0])
    # as ros2 param get prints it ('String value is: ...', or the value alone with --hide-type): a dump's
    # 'quote: ...' line or the topic's messages hold the same text (helper audit of issue 37)
    if not scripts.printed(s, "got", run, [node.initial_quote], f"current quote of {NODE} "
                           f"({short(node.initial_quote)}), as ros2 param get prints it",
                           f"ros2 param get {NODE} quote", whole_lines=True, line_text=get_lines) \
            and node.initial_quote in run.stdout:
        s.amend("got", observed="the quote is in the output, but not on a line of its own as `ros2 param get` "
                "prints it ('String value is: ...'): another command printed it")
    judge_set(s, node, run)
    try:
        judge_dump(s, dump, started, node.parameters(), placeholder)
    finally:
        placeholder.remove_if_left()
    judge_late_node(s, path, scripts.late_by(run), asked_at)


def judge_late_node(s: Session, path, delay: float, asked_at: float | None) -> None:
    """Record ``waits_for_node``: run the script again in a fresh graph with no daemon; the node starts
    ``delay`` s (``kit.scripts.late_by``) after the script's first ``ros2`` command joined the graph, while
    :data:`OTHER_NODE` runs there from the start; its quote must be printed. And the wait must end when the node shows: in the first run, where it was listed all along, the
    script's first ``ros2 param`` command came ``asked_at`` s after the script started (None: none was seen),
    at most :data:`PROMPT`. Run after :func:`judge_dump`: the file this run may write is not the one judged."""
    if (blocker := s.unmet_need("waits_for_node")) is not None:
        s.record("waits_for_node", False, blocker, "")
        return
    with s.part("late node", own_graph=True):
        late: list[ConfigurableQuotePublisher] = []
        msg_type = amazing_quote(s)
        MysteryNode(s, OTHER_NODE)  # listed from the start; closed when the part ends
        run = scripts.run_script_first(s, path, lambda: late.append(ConfigurableQuotePublisher(s, msg_type)),
                                       late_by=delay, timeout=TIMEOUT,
                                       until=lambda out: bool(late) and late[0].initial_quote in out)
        got = late[0].initial_quote in run.run.stdout
        prompt = asked_at is None or asked_at <= PROMPT
        observed = f"{run.describe()}; " + ("it printed the node's quote" if got else
                                            f"it never printed the node's quote ({short(late[0].initial_quote)}; "
                                            f"/{OTHER_NODE} was listed from the start: does the wait look for "
                                            f"{NODE} itself?); it printed: "
                                            f"{scripts.excerpt(run.run.stdout + run.run.stderr)}")
        if not prompt:
            observed += (f"; in the first run, where the daemon listed {NODE} from the start, the first ros2 param "
                         f"command came only {asked_at:.1f} s after the script started: the wait did not end when "
                         "ros2 node list showed the node (does the loop's test ever match? grep -q and the exact "
                         "node name, then break)")
        s.record("waits_for_node", got and prompt, observed,
                 f"the script waits for {NODE}, which joins {delay:.1f} s after its first ros2 command (as long as "
                 f"its first run took; /{OTHER_NODE} runs from the start), and prints its quote (ros2 param get); and it stops waiting once ros2 node "
                 f"list shows the node (first ros2 param command within {PROMPT:.0f} s when the node is there "
                 "from the start)")


def judge_set(s: Session, node: ConfigurableQuotePublisher, run: Any) -> None:
    """Record ``set``: the node accepted quote = NEW_QUOTE and the next messages (send stamps) carry it."""
    expected = f"after your `ros2 param set`, /{CONFIGURABLE_TOPIC} carries the quote {NEW_QUOTE!r}"
    since = node.change_time("quote", NEW_QUOTE)
    if since is None:
        tried = [f"{name} = {value!r}" for _, name, value in node.changes]
        said = [line.strip() for line in (run.stdout + run.stderr).splitlines() if "parameter" in line.lower()]
        s.record("set", False, f"the node's quote was never set to the lesson's text; changes it accepted: "
                 f"{', '.join(tried) or 'none'}; your script said: {scripts.excerpt(' | '.join(said), 200)}",
                 expected, hint=f"{SET_COMMAND} (a string: in double quotes, spelled exactly)")
        return
    with s.phase("observe"):
        later = node.probe.wait_sent_after(since, NEXT_MESSAGES, CONFIGURABLE_PERIOD)
    quotes = [m.quote for m in later[:NEXT_MESSAGES]]
    passed = bool(quotes) and quotes[-1] == NEW_QUOTE
    s.record("set", passed, f"the node accepted the new quote; the next messages said {', '.join(map(short, quotes))}"
             if quotes else "the node accepted the new quote but sent no message after it", expected)


def judge_dump(s: Session, dump, started: float, current: dict[str, Any], placeholder: DumpPlaceholder) -> None:
    """Record ``dump_file`` (written by this run, the dump format, every parameter of the node with its current
    value, ``quote`` aside) and ``dump_after_set``.

    ``current``: the node's parameters when the script has ended (``ros2 param dump`` writes all of them,
    ``use_sim_time`` and ``start_type_description_service`` included: the lesson asks for all). ``placeholder``:
    what was in the file before the run (its own text, or the grader's placeholder), which a dump redirected
    with ``>`` replaces and one appended with ``>>`` keeps.
    """

    expected = (f"{DUMP} written by your script: '{NODE}:' -> 'ros__parameters:' -> every parameter of the node "
                f"({', '.join(sorted(current))})")
    if not dump.is_file() or placeholder.untouched() or dump.stat().st_mtime < started - 1.0:
        state = ("does not exist" if not dump.is_file() or placeholder.untouched() else
                 "was not written by this run (it is older)")
        s.record("dump_file", False, f"{DUMP} {state}", expected,
                 hint=f"ros2 param dump prints the parameters; redirect them: ros2 param dump {NODE} > {DUMP}")
        return
    text = dump.read_text(encoding="utf-8", errors="replace")
    if placeholder.kept(text):
        s.record("dump_file", False, f"{DUMP} still holds what was in it before your script ran "
                 f"({scripts.excerpt(placeholder.before, 80)}), with the dump after it: appended (>>), not "
                 "overwritten", expected, hint=f"`>` overwrites the file: ros2 param dump {NODE} > {DUMP}")
        return
    text, middleware = without_fastdds_log(text)
    aside = (f" (left aside: {len(middleware)} line(s) Fast DDS's logging wrote on stdout, e.g. "
             f"{scripts.excerpt(middleware[0], 100)})") if middleware else ""
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        s.record("dump_file", False, f"{DUMP} is not valid YAML ({str(exc).splitlines()[0]}){aside}", expected)
        return
    values, problem = (params.dump_section(data, NODE) if isinstance(data, dict) and data
                       else (None, f"it holds {scripts.excerpt(text, 120)}"))
    if values is None:
        s.record("dump_file", False, f"{DUMP}: {problem}", expected)
        return
    missing = [name for name in sorted(current) if name not in values]
    wrong = [f"{name} = {values[name]!r} (the node has {current[name]!r})" for name in sorted(current)
             if name != "quote" and name in values and values[name] != current[name]]
    problems = wrong + ([f"missing {', '.join(missing)} (ros2 param dump writes every parameter of the node)"]
                        if missing else [])
    s.record("dump_file", not problems,
             f"{DUMP}: " + ("; ".join(problems) if problems
                            else f"{NODE} -> ros__parameters with {len(values)} parameters") + aside, expected)
    s.record("dump_after_set", values.get("quote") == NEW_QUOTE, f"the dump's quote is {short(str(values.get('quote')))}",
             f"the dump's quote is {NEW_QUOTE!r} (the value after your set)")
