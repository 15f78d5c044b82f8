"""Grader for ``inspect-services`` (tutorial ch. 21; contract in shared/LESSONS.md).

The grader's node ``/oracle_NNN`` (random name) serves ``/what_is_the_point``
(the learner's WhatIsThePoint) and answers each request with a random point,
summing to 42 for a quote about life (:mod:`graders._mystery_services`).
The learner's ``cli/inspect_services.sh`` runs in that graph (kit.scripts); it
is judged on the service list it printed, the requests the server received
and the responses it printed (random values only a real call can show).
A second run, in a fresh graph with no ``ros2`` daemon, starts another oracle only
after the script's first ``ros2`` command has been listening for 1 s
(kit.scripts.run_script_first): ``ros2 service list --spin-time 2`` still lists
it, a list that listens the default 0.5 s cannot.
"""

from __future__ import annotations

from ros2course.kit import Check, Session, scripts
from ._mystery_services import SERVICE, SERVICE_TYPE, PointOracle
from ros2course.kit.topics_services import workspace_types

SCRIPT = "cli/inspect_services.sh"
#: Seconds the script may run: a `ros2` command starts in ~1 s; a call to a missing service waits for ever.
TIMEOUT = 25.0
LIFE_CALL = (f"ros2 service call {SERVICE} {SERVICE_TYPE} "
             "\"{quote: {id: 42, quote: What is the meaning of life, philosopher_name: Douglas}}\"")
OTHER_CALL = (f"ros2 service call {SERVICE} {SERVICE_TYPE} "
              "\"{quote: {id: 7, quote: Use the force, philosopher_name: Ben}}\"")

#: Without a running ``ros2`` daemon (a fresh terminal) ``ros2 service list`` listens for the graph itself
#: for ``--spin-time`` seconds (default 0.5 s, ros2cli ``node/direct.py``): too short on a busy machine. The
#: first run starts a daemon that already lists the oracle, so there the list comes from that daemon; the
#: second run has none, and its oracle starts LATE_BY s after the list's own node joined the graph.
LIST_HINT = ("ros2 service list --spin-time 2, its output printed (no `> /dev/null`, no `| grep`): in the first "
             "run a ros2 daemon already lists the server, so the list is complete when the command runs")
#: Seconds between the script's first ``ros2`` command joining the graph and the second run's oracle: after
#: the default 0.5 s of listening, well inside the 2 s of ``--spin-time 2``.
LATE_BY = 1.0
LATE_HINT = ("give ros2 service list --spin-time 2: with no ros2 daemon running (a fresh terminal, as in this "
             "run), the command listens for the graph itself for only 0.5 s by default, and a server it has "
             "not discovered by then is missing from the list")

SCRIPTED = ("script",)
CHECKS = [
    Check("build", "package_with_interfaces builds with colcon", 1),
    Check("script", f"{SCRIPT} exists and is valid bash", 1),
    Check("ends", "The script ends by itself, with exit code 0", 2,
          "`ros2 service call` ends after one answer unless you give it `-r`; a call to a service that does not "
          "exist waits for ever", needs=SCRIPTED),
    Check("listed", "It prints the services of the graph (ros2 service list)", 1, LIST_HINT, needs=SCRIPTED),
    Check("call_life", f"The server receives a request whose quote contains 'life' (ros2 service call {SERVICE})",
          2, LIFE_CALL, needs=SCRIPTED),
    Check("call_other", "The server receives a request whose quote does not contain 'life'", 2, OTHER_CALL,
          needs=SCRIPTED),
    Check("responses", "It prints the response of each call (the point the server sent)", 2,
          "let `ros2 service call` print to the terminal: no `> /dev/null`, no `| grep`", needs=("call_life",)),
    Check("listed_late", "With no ros2 daemon running, its service list waits for a server discovered late "
          "(--spin-time 2)", 1, LATE_HINT, needs=("listed",)),
]


def grade(s: Session) -> None:
    path = scripts.script(s, "script", SCRIPT)
    srv_type = workspace_types(s, "srv", "WhatIsThePoint")
    oracle = PointOracle(s, srv_type)
    # a daemon that already lists the oracle, as in a learner's terminal (kit.scripts.ros2_daemon)
    run = scripts.run_script(s, path, timeout=TIMEOUT, daemon_sees=oracle.listed_services())
    scripts.ended(s, "ends", run, "it ends by itself with exit code 0 (each `ros2 service call` ends after one answer)")
    scripts.printed(s, "listed", run, oracle.listed_services(), "list of services", "ros2 service list --spin-time 2")
    calls = oracle.calls()
    received = "; ".join(c.describe() for c in calls[:4]) or "no request at all"
    for check_id, about_life, command in (("call_life", True, LIFE_CALL), ("call_other", False, OTHER_CALL)):
        wanted = [c for c in calls if c.about_life == about_life]
        kind = "contains 'life'" if about_life else "does not contain 'life'"
        s.record(check_id, bool(wanted), f"{SERVICE} received {len(calls)} request(s): {received}",
                 f"{SERVICE} receives a {SERVICE_TYPE} request whose quote {kind}",
                 hint=f"for example: {command}" if calls else
                 f"no call reached {SERVICE}: check the service name and type (`ros2 service type {SERVICE}`); "
                 f"for example: {command}")
    missing = [c for c in calls if c.printed_point() not in run.stdout]
    expected = "each response `ros2 service call` prints, e.g. " \
               + (calls[0].printed_point() if calls else "Point(x=..., y=..., z=...)")
    if missing:
        s.record("responses", False, f"the server answered {missing[0].describe()} with {missing[0].printed_point()}, "
                 f"which your script did not print; it printed: {scripts.excerpt(run.stdout)}", expected)
    else:
        s.record("responses", True, f"it printed the {len(calls)} response(s) the server sent", expected)
    judge_late_list(s, path, srv_type)


def judge_late_list(s: Session, path, srv_type) -> None:
    """Record ``listed_late``: run the script again in a fresh graph with no daemon; the oracle starts
    :data:`LATE_BY` s after the script's first ``ros2`` command joined the graph; its services must be listed."""
    if (blocker := s.unmet_need("listed_late")) is not None:
        s.record("listed_late", False, blocker, "")
        return
    with s.part("late server", own_graph=True):
        oracles: list[PointOracle] = []
        late = scripts.run_script_first(s, path, lambda: oracles.append(PointOracle(s, srv_type)),
                                        late_by=LATE_BY, timeout=TIMEOUT,
                                        until=lambda out: bool(oracles) and all(
                                            name in out for name in oracles[0].listed_services()))
        wanted = oracles[0].listed_services()
        missing = [name for name in wanted if name not in late.run.stdout]
        expected = (f"with no ros2 daemon running, the list names the server that joined {LATE_BY:.0f} s after "
                    "the command started listening (`ros2 service list --spin-time 2` listens 2 s)")
        s.record("listed_late", not missing,
                 f"{late.describe()}; " + (f"the list lacked {', '.join(missing)}; it printed: "
                                           f"{scripts.excerpt(late.run.stdout)}" if missing
                                           else f"it listed {', '.join(wanted)}"), expected)
