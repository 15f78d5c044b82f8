"""Grader for ``service-server-client`` (seed ch. 20-21; contract in shared/LESSONS.md).

Black-box, and the grader plays the other side each time:

* for the **server** it is the client: it calls ``/what_is_the_point`` with
  quotes that contain "life" in several spellings (LIFE, Life, lIfE) and
  quotes that do not (one with "Life" in the philosopher's name only), and
  checks whether the returned point's coordinates sum to 42 (± 1e-6);
* for the **client** it is the server: it starts the client before the
  service exists (the client must say it waits), then offers the service
  with answers it can recognise (distinctive points it then looks for in the
  client's log), measures the call rate (2 Hz), and finally answers 1 s
  late: a client that keeps its executor free (``call_async`` + a done
  callback) still calls every 0.5 s, one that blocks on the answer
  (``spin_until_future_complete`` or a busy wait inside its timer callback,
  or the synchronous ``call()``) does not.
"""

from __future__ import annotations

from ros2course import kit
from ros2course.kit import Check, Session, checks, parts
from ros2course.kit import services
from ros2course.kit import topics_services as ts

PACKAGE = "python_package_that_uses_the_services"
SERVER_EXE = "what_is_the_point_service_server_node"
SERVER_NODE = "what_is_the_point_service_server"
CLIENT_EXE = "what_is_the_point_service_client_node"
CLIENT_NODE = "what_is_the_point_service_client"
SERVICE = "/what_is_the_point"
SRV_TYPE = "package_with_interfaces/srv/WhatIsThePoint"
PERIOD = 0.5  # seconds between calls, seed ch. 20.5.6
CALLS = 6  # calls -> 5 intervals, the minimum LESSONS.md asks for
SUM_TOLERANCE = 1e-6  # |x + y + z - 42|
LATE_ANSWER = 1.0  # seconds: twice the call period, so a blocked client halves its rate
#: Seconds the service stays missing after the client's first "waiting" record: a client that says so at
#: most once a second says it three or four times, one that says it at every 0.5 s tick six.
THROTTLE_WINDOW = 2.5
#: Calls per quote. The seed's server draws x and y at random, so a rule right for most draws passes one call:
#: ``z = 42 % (x + y)`` sums to 42 whenever x + y > 21, 85 % of the reference's draws; 50 calls leave it
#: unseen 0.03 % of the time. The other quotes, 5 calls each (a point that sums to 42 only sometimes).
SUM_REPEATS = 50
REPEATS = 5

#: (quote, philosopher, does the quote contain "life" in any case?, the quote's id)
LOWERCASE_LIFE = ("what is the meaning of life, then?", "Monty Python", True, 4201)
OTHER_CASES = [
    ("LIFE, UH, FINDS A WAY.", "Ian Malcolm", True, 4202),
    ("Life is like a box of chocolates.", "Forrest Gump", True, 4203),
    ("It is a lIfE of potatoes, always potatoes.", "a young Maltese potato farmer", True, 4204),
    # the lesson: the quote text "contains" life: inside a longer word too (a whole-word regex failed no case)
    ("The AFTERLIFE is overrated.", "a ghost", True, 4205),
]
NO_LIFE = [
    ("So you're telling me there's a chance.", "Lloyd", False, 4301),
    ("I dream of potatoes.", "Life Coach Larry", False, 4302),  # 'Life' only in the philosopher's name
    ("no match", "Nobody", False, 4303),
]

SERVER = {"part": "server", "needs": ("server_executable",)}
CLIENT = {"part": "client", "needs": ("client_executable",)}

#: Seconds of observation the contract needs, on the client's clock (the server half runs at the
#: same time in a graph of its own and is shorter): its first "waiting" record (within one 0.5 s
#: tick of starting) and the throttle window after it, then twice "the next tick + 5 intervals at 2 Hz": once with prompt answers
#: (rate, logged points), once with answers LATE_ANSWER s late (does it keep calling?).
WINDOW = PERIOD + THROTTLE_WINDOW + 2 * (PERIOD + (CALLS - 1) * PERIOD)

CHECKS = [
    Check("build", "The packages build with colcon", 1),
    checks.interfaces_depend(),
    *checks.started("server", PACKAGE, SERVER_EXE, SERVER_NODE, part="server"),
    Check("service_name_type", "It serves /what_is_the_point of type package_with_interfaces/srv/WhatIsThePoint", 2,
          "self.create_service(srv_type=WhatIsThePoint, srv_name='/what_is_the_point', callback=...)", **SERVER),
    Check("life_sum_42", "A quote containing 'life' gets a point whose coordinates sum to 42", 2,
          "in the callback, test request.quote.quote and make z = 42 - (x + y)", **SERVER),
    Check("life_any_case", "'LIFE', 'Life', 'lIfE' count as 'life' too, and so does 'AFTERLIFE' (it contains it)", 2,
          "compare in one case, and look for the text anywhere: 'life' in request.quote.quote.lower()", **SERVER),
    Check("no_life_not_42", "Any other quote gets a point whose coordinates do not sum to 42", 2,
          "look at the quote's text (request.quote.quote), not the philosopher's name; "
          "if a random point happens to sum to 42, move it", **SERVER),
    checks.ctrl_c("server_sigint_exit", "the server", **SERVER),
    *checks.started("client", PACKAGE, CLIENT_EXE, CLIENT_NODE, part="client"),
    Check("client_waits", "Before the service exists, the client logs that it is waiting for it", 2,
          "until self.service_client.service_is_ready() is true, log e.g. "
          "'service /what_is_the_point not available, waiting...' (and send nothing)", **CLIENT),
    Check("client_waits_throttled", "It says so at most once a second", 1,
          "log the waiting record with throttle_duration_sec=1.0: the 0.5 s timer that checks service_is_ready() "
          "would say it twice a second", part="client", needs=("client_waits",)),
    Check("client_calls", "Once the service exists, the client calls /what_is_the_point", 2,
          "create the client with srv_type=WhatIsThePoint, srv_name='/what_is_the_point' "
          "and call self.service_client.call_async(request) in a timer callback", **CLIENT),
    Check("client_quiet_while_missing", "It sends no request while the service is missing", 1,
          "return from the timer callback while service_is_ready() is false: a request sent then reaches no one",
          part="client", needs=("client_calls",)),
    Check("client_rate", "It calls twice a second (every 0.5 s)", 2,
          "self.create_timer(0.5, self.timer_callback), one call_async per tick", part="client",
          needs=("client_calls",)),
    Check("client_logs_points", "It logs every point the server returns", 2,
          "future.add_done_callback(self.process_response); in it, log future.result().point with the logger",
          part="client", needs=("client_calls",)),
    Check("client_keeps_calling_when_slow",
          "While an answer is late, it still calls every 0.5 s (call_async never blocks the executor)", 3,
          "don't wait for the answer inside the timer callback (no spin_until_future_complete, no call(), "
          "no loop on future.done()): return at once and let a done callback handle the response",
          part="client", needs=("client_calls",)),
    checks.ctrl_c("client_sigint_exit", "the client", **CLIENT),
]


def _grade_server(s: Session, srv_type: type) -> None:
    path = kit.executable(s, "server_executable", PACKAGE, SERVER_EXE)
    node = kit.start_node(s, "server_node_name", path, SERVER_NODE, sigint_check="server_sigint_exit",
                          need_node=False)
    target, where = ts.own_endpoint(s, "service_name_type", node, "services", SERVICE, SRV_TYPE,
                                    none=f"no service of type {SRV_TYPE} to call", where="called at")

    ask = services.quote_to_point(s, srv_type, target, node, total=42.0, tolerance=SUM_TOLERANCE, repeats=REPEATS)
    ask_sum = services.quote_to_point(s, srv_type, target, node, total=42.0, tolerance=SUM_TOLERANCE,
                                      repeats=SUM_REPEATS)
    with s.phase("observe"):
        services.answers(s, "life_sum_42", ask_sum, [LOWERCASE_LIFE], "coordinates summing to 42 (± 1e-6)", where)
        services.answers(s, "life_any_case", ask, OTHER_CASES,
                         "each point sums to 42 (± 1e-6): 'life' in any case, inside a word too", where)
        services.answers(s, "no_life_not_42", ask, NO_LIFE, "no point sums to 42 (the quote text has no 'life')",
                         where)


def _quiet_while_missing(s: Session, server: ts.DeferredServer) -> None:
    """``client_quiet_while_missing`` from the first request the service took: a client numbers its requests
    from 1 (``rmw_request_id_t.sequence_number``, one count per client; rmw_fastrtps takes it from the request
    writer's sample number), and a request sent while no server existed was matched by no reader and lost, so
    a first request numbered n > 1 means n - 1 were sent while the service was missing. Recorded only once a
    call arrived (``needs`` client_calls); a number of 0 (an rmw that does not give one) is not held against it.
    """
    if not server.sequence_numbers:
        return
    first = server.sequence_numbers[0]
    expected = "no request until the service exists: the first request it receives is the client's request 1"
    if first > 1:
        s.record("client_quiet_while_missing", False,
                 f"the first request that reached {SERVICE} was the client's request {first}: "
                 f"{first - 1} were sent while the service did not exist (lost: nothing answers them)", expected)
    else:
        s.record("client_quiet_while_missing", True, "the first request it sent reached the service", expected)


def _grade_client(s: Session, srv_type: type) -> None:
    path = kit.executable(s, "client_executable", PACKAGE, CLIENT_EXE)
    rosout = s.graph.rosout()  # the part's own graph
    # Made before the client starts, so it closes after the client's Ctrl+C (closing actions run newest first):
    # the client is stopped while the service still exists, as a learner would stop it.
    server = ts.stand_in_server(s, srv_type, SERVICE, services.point_answers(s.random))
    node = kit.start_node(s, "client_node_name", path, CLIENT_NODE, sigint_check="client_sigint_exit",
                          need_node=False)
    if services.says_it_waits(s, "client_waits", rosout, node, SERVICE):  # 1. no service yet
        services.waits_throttled(s, "client_waits_throttled", rosout, node, node_name=CLIENT_NODE,
                                 window=THROTTLE_WINDOW)
    server.offer()  # 2. prompt answers: the calls, their rate, the points in the log
    services.calls(s, "client_calls", "client_rate", server, node, service=SERVICE, count=CALLS, period=PERIOD)
    _quiet_while_missing(s, server)
    services.logs_answers(s, "client_logs_points", server, rosout, node)
    # 3. late answers: a client that does not block keeps calling every 0.5 s meanwhile
    services.keeps_calling(s, "client_keeps_calling_when_slow", server, node, count=CALLS, period=PERIOD,
                           late=LATE_ANSWER)


def grade(s: Session) -> None:
    """Grade the server (as its client) and, at the same time, the client (as its server).

    Each runs in a private graph of its own, so the two halves overlap
    (:func:`ros2course.kit.parts.at_once`); the client, started from the main
    thread, gets the parent-death signal.
    """
    kit.depends(s, "depends", PACKAGE, ("rclpy", ts.INTERFACES))
    srv_type = ts.workspace_types(s, "srv", "WhatIsThePoint")
    parts.at_once(s, "server", lambda: _grade_server(s, srv_type),
                  "client", lambda: _grade_client(s, srv_type), own_graphs={"client"})
