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

import concurrent.futures
import random
import re
import time

from course.run.probes import LATE_DELIVERY, call_service, wait_until
from graders import kit
from graders.kit import RATE_TOLERANCE, Check, GradingSession
from graders.kit import topics_services as ts

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
#: Seconds of extra patience for calls that were sent on time but delivered late: a reliable
#: DDS sample lost on a loaded machine is repaired after the writer's next heartbeat (Fast DDS
#: default period: 3 s) and holds back the samples after it. Rates use the send stamps, so
#: waiting longer never changes a verdict; it only runs when calls are missing.
LATE_DELIVERY_GRACE = LATE_DELIVERY
#: A log record saying the client gave up on a late answer (the seed's client: "Service Future
#: canceled. The Node took too long to process the service call...").
CANCELLED = re.compile(r"cancel|too long|took more than|timed? ?out", re.IGNORECASE)
WAITING = re.compile(r"wait|availab", re.IGNORECASE)

#: (quote, philosopher, does the quote contain "life" in any case?)
LOWERCASE_LIFE = ("what is the meaning of life, then?", "Monty Python", True)
OTHER_CASES = [
    ("LIFE, UH, FINDS A WAY.", "Ian Malcolm", True),
    ("Life is like a box of chocolates.", "Forrest Gump", True),
    ("It is a lIfE of potatoes, always potatoes.", "a young Maltese potato farmer", True),
]
NO_LIFE = [
    ("So you're telling me there's a chance.", "Lloyd", False),
    ("I dream of potatoes.", "Life Coach Larry", False),  # 'Life' only in the philosopher's name
    ("no match", "Nobody", False),
]

SERVER = {"part": "server", "needs": ("server_executable",)}
CLIENT = {"part": "client", "needs": ("client_executable",)}
SIGINT_HINT = "catch (KeyboardInterrupt, ExternalShutdownException) around rclpy.spin()"

#: Seconds of observation the contract needs, on the client's clock (the server half runs at the
#: same time in a graph of its own and is shorter): its first "waiting" record (within one 0.5 s
#: tick of starting), then twice "the next tick + 5 intervals at 2 Hz": once with prompt answers
#: (rate, logged points), once with answers LATE_ANSWER s late (does it keep calling?).
WINDOW = PERIOD + 2 * (PERIOD + (CALLS - 1) * PERIOD)

CHECKS = [
    Check("build", "The packages build with colcon", 1),
    Check("depends", "package.xml depends on rclpy and package_with_interfaces", 1,
          "add <depend>rclpy</depend> and <depend>package_with_interfaces</depend> to package.xml (seed ch. 18.1)"),
    Check("server_executable", "ros2 run finds what_is_the_point_service_server_node", 1,
          "register 'what_is_the_point_service_server_node = python_package_that_uses_the_services."
          "what_is_the_point_service_server_node:main' in console_scripts, then colcon build", part="server"),
    Check("server_node_name", "A node named what_is_the_point_service_server starts", 1,
          "pass 'what_is_the_point_service_server' to super().__init__()", **SERVER),
    Check("service_name_type", "It serves /what_is_the_point of type package_with_interfaces/srv/WhatIsThePoint", 2,
          "self.create_service(srv_type=WhatIsThePoint, srv_name='/what_is_the_point', callback=...)", **SERVER),
    Check("life_sum_42", "A quote containing 'life' gets a point whose coordinates sum to 42", 2,
          "in the callback, test request.quote.quote and make z = 42 - (x + y)", **SERVER),
    Check("life_any_case", "'LIFE', 'Life', 'lIfE' count as 'life' too", 2,
          "compare in one case: 'life' in request.quote.quote.lower()", **SERVER),
    Check("no_life_not_42", "Any other quote gets a point whose coordinates do not sum to 42", 2,
          "look at the quote's text (request.quote.quote), not the philosopher's name; "
          "if a random point happens to sum to 42, move it", **SERVER),
    Check("server_sigint_exit", "Ctrl+C ends the server with exit code 0 and no traceback", 1, SIGINT_HINT, **SERVER),
    Check("client_executable", "ros2 run finds what_is_the_point_service_client_node", 1,
          "register 'what_is_the_point_service_client_node = python_package_that_uses_the_services."
          "what_is_the_point_service_client_node:main' in console_scripts, then colcon build", part="client"),
    Check("client_node_name", "A node named what_is_the_point_service_client starts", 1,
          "pass 'what_is_the_point_service_client' to super().__init__()", **CLIENT),
    Check("client_waits", "Before the service exists, the client logs that it is waiting for it", 2,
          "until self.service_client.service_is_ready() is true, log e.g. "
          "'service /what_is_the_point not available, waiting...' (and send nothing)", **CLIENT),
    Check("client_calls", "Once the service exists, the client calls /what_is_the_point", 2,
          "create the client with srv_type=WhatIsThePoint, srv_name='/what_is_the_point' "
          "and call self.service_client.call_async(request) in a timer callback", **CLIENT),
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
    Check("client_sigint_exit", "Ctrl+C ends the client with exit code 0 and no traceback", 1, SIGINT_HINT, **CLIENT),
]


def _point_text(point) -> str:
    return f"({point.x:.6g}, {point.y:.6g}, {point.z:.6g})"


def _grade_server(s: GradingSession, srv_type: type) -> None:
    path = kit.executable(s, "server_executable", PACKAGE, SERVER_EXE)
    node = kit.start_node(s, "server_node_name", path, SERVER_NODE, sigint_check="server_sigint_exit",
                          need_node=False)
    found = ts.wait_for_endpoint(s, node.name, "services", SERVICE, 3.0, abort=node.ended)
    s.record("service_name_type", SRV_TYPE in found.get(SERVICE, []),
             f"{node.name or 'the node'} serves: {ts.describe_endpoints(found)}", f"{SERVICE} [{SRV_TYPE}]")
    target = ts.pick_endpoint(found, SERVICE, SRV_TYPE)
    if target is None:
        raise kit.Unmet(f"no service of type {SRV_TYPE} to call")
    where = "" if target == SERVICE else f" (called at {target}, the name your server uses)"

    def ask(case: tuple[str, str, bool], quote_id: int) -> tuple[bool, str]:
        """Call once; returns (answer as expected, description)."""
        text, philosopher, life = case
        request = srv_type.Request()
        request.quote.id = quote_id
        request.quote.quote = text
        request.quote.philosopher_name = philosopher
        label = f"'{text}' -- {philosopher}"
        if node.ended():
            return False, f"{label}: not asked, {kit.process_state(node.proc)}"
        try:
            response = call_service(s.ros, srv_type, target, request, timeout=3.0)
        except TimeoutError as exc:
            return False, f"{label}: {exc}; {kit.process_state(node.proc)}"
        total = response.point.x + response.point.y + response.point.z
        is_42 = abs(total - 42.0) <= SUM_TOLERANCE
        return is_42 == life, f"{label}: point {_point_text(response.point)}, sum {total:.9g}"

    with s.phase("observe"):
        ok, text = ask(LOWERCASE_LIFE, 4201)
        s.record("life_sum_42", ok, text + where, "coordinates summing to 42 (± 1e-6)")
        results = [ask(case, 4202 + i) for i, case in enumerate(OTHER_CASES)]
        passed = sum(r[0] for r in results)
        s.record("life_any_case", passed == len(results), "; ".join(r[1] for r in results) + where,
                 "each point sums to 42 (± 1e-6): 'life' in any case", fraction=passed / len(results))
        results = [ask(case, 4301 + i) for i, case in enumerate(NO_LIFE)]
        passed = sum(r[0] for r in results)
        s.record("no_life_not_42", passed == len(results), "; ".join(r[1] for r in results) + where,
                 "no point sums to 42 (the quote text has no 'life')", fraction=passed / len(results))


def _grade_client(s: GradingSession, srv_type: type, graph) -> None:
    path = kit.executable(s, "client_executable", PACKAGE, CLIENT_EXE)
    rosout = graph.rosout()
    rng = random.Random()
    base = [rng.randrange(100, 900) for _ in range(3)]

    def answer(index: int, request, response):
        # Quarter steps are exact in binary and short in decimal: easy to recognise in any format.
        response.point.x = base[0] + index + 0.25
        response.point.y = -(base[1] + index + 0.5)
        response.point.z = base[2] + 0.75 * ((index % 3) + 1)
        return response

    # Made before the client starts, so it closes after the client's Ctrl+C (closing actions run newest first):
    # the client is stopped while the service still exists, as a learner would stop it.
    server = ts.stand_in_server(s, srv_type, SERVICE, answer, graph)
    node = kit.start_node(s, "client_node_name", path, CLIENT_NODE, sigint_check="client_sigint_exit", graph=graph,
                          need_node=False)

    def waiting_records():
        return rosout.records(match=lambda text: WAITING.search(text) is not None)

    # 1. No service yet: the client must say that it waits.
    with s.phase("observe"):
        wait_until(lambda: bool(waiting_records()), 3.0, abort=node.ended)
    said = waiting_records()
    before = rosout.records()
    if said:
        s.record("client_waits", True, f"logged '{said[0].msg.strip()}' while {SERVICE} did not exist",
                 "a log record saying it waits for the service")
    else:
        shown = " | ".join(r.msg.strip()[:80] for r in before[:3]) or "no log records"
        s.record("client_waits", False, f"in 3 s without the service: {shown}; {kit.process_state(node.proc)}",
                 f"a log record (e.g. 'service {SERVICE} not available, waiting...') while the service is missing")
    # 2. Offer the service; answer at once with points the client's log must show.
    server.offer()
    _grade_calls(s, server, rosout, node)


def _grade_calls(s: GradingSession, server: ts.DeferredServer, rosout, node: kit.StartedNode) -> None:
    """Calls, their rate, the logged points, then calls while answers are late (seconds as named)."""
    proc = node.proc
    offered = time.monotonic()
    with s.phase("observe"):
        wait_until(lambda: len(server.calls) >= CALLS, CALLS * PERIOD + 2.0 + LATE_DELIVERY_GRACE, abort=node.ended)
    calls = server.calls_since(offered)
    expected_calls = f"calls to {SERVICE} within {CALLS * PERIOD + 2.0 + LATE_DELIVERY_GRACE:.0f} s of it appearing"
    if not calls:
        s.record("client_calls", False, f"no call in {time.monotonic() - offered:.1f} s; {kit.process_state(proc)}",
                 expected_calls)
        s.require("client_calls")
    first = calls[0][0] - offered
    s.record("client_calls", True, f"{len(calls)} call(s), the first {first:.2f} s after the service appeared",
             expected_calls)

    kit.rate(s, "client_rate", server.send_stamps(offered, CALLS), period=PERIOD, needed=CALLS,
             waited=time.monotonic() - offered, noun="call", source="the requests' send stamps",
             few_note=f"; {kit.process_state(proc)}")

    # The points sent so far must show up in the client's log (give the last one a moment).
    # A client that cancels a call still unanswered at its next tick (the seed's client does,
    # and logs it) legitimately never logs an answer that reached it late on a loaded machine:
    # each such cancel it logged excuses one missing point.
    def points_sent():
        return [(r.point.x, r.point.y, r.point.z) for _, r in server.answers]

    def logged(point):
        return any(ts.has_point(rec.msg, point) for rec in rosout.records())

    def cancels():
        return rosout.records(match=lambda text: CANCELLED.search(text) is not None)

    sent = points_sent()
    with s.phase("observe"):
        # 1 s for the last answer's log record, more only while records are missing (LATE_DELIVERY_GRACE).
        wait_until(lambda: sum(not logged(p) for p in sent) <= len(cancels()), 1.0 + LATE_DELIVERY_GRACE,
                   abort=node.ended)
    found = [p for p in sent if logged(p)]
    missing = [p for p in sent if p not in found]
    cancelled = cancels()
    excused = min(len(missing), len(cancelled))
    shown = ", ".join(f"({x:g}, {y:g}, {z:g})" for x, y, z in sent[:3]) + (", ..." if len(sent) > 3 else "")
    expected_logs = ("each returned point in a log record (the logger, not print()); an answer the client "
                     "cancelled as late, and said so in its log, may be missing")
    if found and len(missing) == excused:
        late = (f"; {excused} answer(s) came late and the client cancelled them "
                f"('{cancelled[0].msg.strip()[:80]}')" if excused else "")
        s.record("client_logs_points", True, f"{len(found)} of the {len(sent)} points sent were logged, e.g. "
                 f"'{_first_line_with(rosout, found[0])}'{late}", expected_logs)
    else:
        recent = " | ".join(r.msg.strip().replace("\n", " ")[:80] for r in rosout.records()[-2:]) or "none"
        first = missing[0] if missing else (0.0, 0.0, 0.0)
        s.record("client_logs_points", False,
                 f"{len(found)} of the {len(sent)} points sent ({shown}) found in the log; missing e.g. "
                 f"({first[0]:g}, {first[1]:g}, {first[2]:g}); last records: {recent}",
                 expected_logs, fraction=len(found) / len(sent) if sent else 0.0)

    # 3. Answer late: a client that does not block keeps calling every 0.5 s meanwhile.
    server.delay = LATE_ANSWER
    slow_begin = time.monotonic()
    window = CALLS * PERIOD + 1.0 + LATE_DELIVERY_GRACE
    with s.phase("observe"):
        wait_until(lambda: len(server.calls_since(slow_begin)) >= CALLS, window, abort=node.ended)
    late = server.calls_since(slow_begin)
    stats = server.rate(slow_begin, CALLS)
    expected_slow = (f"calls keep coming every {PERIOD:.1f} s (± {RATE_TOLERANCE:.0%}, over {CALLS - 1} intervals) "
                     f"while each answer takes {LATE_ANSWER:.1f} s")
    if stats is not None and stats.samples >= CALLS - 1 and stats.within(1.0 / PERIOD, RATE_TOLERANCE):
        s.record("client_keeps_calling_when_slow", True, f"answers {LATE_ANSWER:.1f} s late: {stats.describe()}",
                 expected_slow)
    else:
        what = stats.describe() if stats else f"{len(late)} call(s)"
        s.record("client_keeps_calling_when_slow", False,
                 f"with answers {LATE_ANSWER:.1f} s late: {what} in {time.monotonic() - slow_begin:.1f} s; "
                 "the client seems to wait for each answer before calling again (a blocked executor?); "
                 + kit.process_state(proc), expected_slow)


def _first_line_with(rosout, point) -> str:
    for rec in rosout.records():
        if ts.has_point(rec.msg, point):
            lines = [line.strip() for line in rec.msg.strip().splitlines() if line.strip()]
            return " ".join(lines)[:100]
    return ""


def grade(s: GradingSession) -> None:
    """Grade the server (as its client) and, at the same time, the client (as its server).

    Each executable runs in a private graph of its own (so neither sees the
    other, and neither waits for the other's discovery), which lets the two
    halves overlap: the check takes about as long as the client's half. The
    client is started from this (main) thread, so it gets the parent-death
    signal; the server half runs on a worker thread, in a part of its own
    (``s.part`` keeps each thread's closing actions apart).
    """
    kit.depends(s, "depends", PACKAGE, ("rclpy", ts.INTERFACES))
    srv_type = ts.workspace_types(s, "srv", "WhatIsThePoint")

    def server_half() -> None:
        with s.part("server"):
            _grade_server(s, srv_type)

    with concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="ros2course-server-half") as pool:
        server_done = pool.submit(server_half)
        try:
            with s.part("client"):
                _grade_client(s, srv_type, s.new_graph())
        finally:
            server_done.result()  # re-raises a grader fault of the server half
