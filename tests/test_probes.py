"""ros2course.run.probes: rate maths, and the probes against real learner-side nodes.

Each ROS test opens a :class:`RosSession` (private domain) and starts a tiny
rclpy script with :class:`LearnerProcess` in that domain.
"""

from __future__ import annotations

import math
import os
import sys
import textwrap

import pytest

from ros2course.run.probes import RateStats, wait_until

PY = sys.executable


# --- RateStats (no ROS) ----------------------------------------------------------


def test_rate_stats_known_times():
    stats = RateStats.from_times([10.0, 11.0, 13.0, 16.0])  # deltas 1, 2, 3
    assert stats.samples == 3
    assert stats.mean_period == pytest.approx(2.0)
    assert stats.rate_hz == pytest.approx(0.5)
    assert stats.min_period == pytest.approx(1.0)
    assert stats.max_period == pytest.approx(3.0)
    # population standard deviation (ros2 topic hz): sqrt(((1-2)^2 + 0 + (3-2)^2) / 3)
    assert stats.std_dev == pytest.approx(math.sqrt(2.0 / 3.0))


def test_rate_stats_counts_messages_the_reader_missed_by_sequence_number():
    # a 500 Hz publisher; the reader lost messages 3, 4 and 8 (a loaded machine): by the times alone
    # the rate looks 30 % low, by the publisher's sequence numbers it is what was published
    sequence = [1, 2, 5, 6, 7, 9, 10]
    times = [(n - 1) * 0.002 for n in sequence]
    assert RateStats.from_times(times).rate_hz == pytest.approx(500 * 6 / 9)
    stats = RateStats.from_times(times, sequence)
    assert stats.rate_hz == pytest.approx(500.0)
    assert (stats.samples, stats.missed) == (9, 3)
    assert stats.std_dev == pytest.approx(0.0, abs=1e-12)
    assert "3 message(s) the grader's reader missed" in stats.describe()
    # numbers that do not increase (two writers, or none given) fall back to the times alone
    for unusable in ([1, 2, 5, 6, 7, 9, 9], [1, 2, 5, None, 7, 9, 10], [1, 2]):
        fallback = RateStats.from_times(times, unusable)
        assert (fallback.samples, fallback.missed) == (6, 0)


def test_rate_stats_regular_and_within():
    times = [i * 0.5 for i in range(7)]
    stats = RateStats.from_times(times)
    assert stats.samples == 6
    assert stats.rate_hz == pytest.approx(2.0)
    assert stats.std_dev == pytest.approx(0.0, abs=1e-12)
    assert stats.within(2.0, 0.15)
    assert stats.within(2.0 * 1.1, 0.15)  # period 0.4545: |0.5 - 0.4545| = 0.045 <= 0.068
    assert not stats.within(1.0, 0.15)
    assert not stats.within(4.0, 0.15)
    assert stats.describe().startswith("2.00 Hz (mean period 0.500 s")


def test_rate_stats_edge_cases():
    assert RateStats.from_times([]) is None
    assert RateStats.from_times([1.0]) is None
    same = RateStats.from_times([1.0, 1.0, 1.0])
    assert same.rate_hz == math.inf and same.mean_period == 0.0


# --- ROS ---------------------------------------------------------------------------

@pytest.fixture
def ros_env():
    pytest.importorskip("rclpy")
    from ros2course.ros import env as env_mod  # noqa: PLC0415

    env = env_mod.activate()
    return env


@pytest.fixture
def learners(tmp_path):
    """Start learner scripts; every one is stopped at the end of the test."""
    from ros2course.run.process import LearnerProcess  # noqa: PLC0415

    started = []

    def start(session, name: str, code: str, env: dict[str, str]) -> LearnerProcess:
        script = tmp_path / f"{name}.py"
        script.write_text(textwrap.dedent(code), encoding="utf-8")
        proc = LearnerProcess([PY, str(script)], session.learner_env(env), tmp_path / "logs", name,
                              ros_sigint=True)
        started.append(proc)
        return proc.start()

    yield start
    for proc in started:
        proc.stop(sigint_timeout=3.0, sigterm_timeout=2.0)
    from ros2course.run.process import sweep_stale_fastdds_shm  # noqa: PLC0415

    sweep_stale_fastdds_shm()


def died(proc):
    """abort= predicate: the learner process has exited."""
    return lambda: proc.poll() is not None


def describe(proc) -> str:
    return f"exit {proc.poll()}; stderr: {proc.stderr()[-1500:]}"


TALKER = """
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.node import Node
    from std_msgs.msg import String

    class Talker(Node):
        def __init__(self):
            super().__init__("test_talker")
            self.pub = self.create_publisher(String, "chatter", 10)
            self.n = 0
            self.timer = self.create_timer(0.1, self.tick)

        def tick(self):
            self.pub.publish(String(data=f"hello {self.n}"))
            self.n += 1

    try:
        rclpy.init()
        rclpy.spin(Talker())
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
"""


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_topic_probe_rate(ros_env, learners):
    from std_msgs.msg import String  # noqa: PLC0415

    from ros2course.run.probes import RosSession  # noqa: PLC0415

    with RosSession() as session:
        probe = session.topic("/chatter", String)
        proc = learners(session, "talker", TALKER, ros_env)
        assert session.wait_for_node("test_talker", 15.0, abort=died(proc)), describe(proc)
        assert probe.wait_for_count(31, 20.0, abort=died(proc)), f"{len(probe.samples())} messages; {describe(proc)}"
        stats = probe.rate()
        assert stats is not None and stats.samples >= 30
        assert stats.within(10.0, 0.10), stats.describe()
        texts = [m.data for m in probe.messages()]
        first = int(texts[0].split()[1])
        assert texts[:10] == [f"hello {first + i}" for i in range(10)]  # in order, none lost
        # the publication sequence number counts the writer's messages from 1, heard or not (what
        # kit.quotes.counts_from_zero and the nav2 grader judge a first message heard by): "hello n" is number n + 1
        numbers = probe.sequence_numbers()
        assert numbers[:10] == [first + 1 + i for i in range(10)], (numbers[:10], texts[:10])
        assert "/chatter" in session.topic_types()
        assert session.topic_types()["/chatter"] == ["std_msgs/msg/String"]
        assert "/test_talker" in session.node_names()
        assert all(not name.split("/")[-1].startswith("_") for name in session.node_names())
        report = proc.stop(sigint_timeout=5.0)
        assert report.signal_used == "SIGINT" and report.returncode == 0, report


NAMED_NODE = """
    import sys
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.node import Node

    try:
        rclpy.init()
        rclpy.spin(Node(sys.argv[1] if len(sys.argv) > 1 else "isolated_node"))
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
"""


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_two_sessions_are_isolated(ros_env, learners):
    from ros2course.run.probes import RosSession  # noqa: PLC0415

    with RosSession() as one, RosSession() as two:
        assert one.domain_id != two.domain_id
        assert 1 <= one.domain_id <= 100 and 1 <= two.domain_id <= 100
        assert one.learner_env({})["ROS_DOMAIN_ID"] == str(one.domain_id)
        proc = learners(one, "isolated", NAMED_NODE, ros_env)
        assert one.wait_for_node("isolated_node", 15.0, abort=died(proc)), describe(proc)
        # well past discovery in the first session; never visible in the second
        assert not two.wait_for_node("isolated_node", 3.0)
        assert "/isolated_node" not in two.node_names()
        assert "/isolated_node" in one.node_names()


LOGGER = """
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.node import Node

    try:
        rclpy.init()
        node = Node("chatty")
        node.get_logger().info("hello from the learner")
        node.get_logger().warning("careful now")
        timer = node.create_timer(0.2, lambda: node.get_logger().info("tick"))
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
"""


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_rosout_probe_receives_learner_records(ros_env, learners):
    from ros2course.run.probes import RosSession  # noqa: PLC0415

    with RosSession() as session:
        rosout = session.rosout()
        proc = learners(session, "chatty", LOGGER, ros_env)
        # the two first records were logged before the probe matched: transient local replays them
        assert wait_until(lambda: rosout.records(node="chatty", match=lambda m: m == "careful now"), 15.0,
                          abort=died(proc)), f"loggers seen: {rosout.loggers()}; {describe(proc)}"
        hello = rosout.records(node="chatty", level=20, match=lambda m: m == "hello from the learner")
        assert len(hello) == 1
        assert hello[0].name == "chatty" and hello[0].level == 20
        warn = rosout.records(node="chatty", match=lambda m: m == "careful now")
        assert [r.level for r in warn] == [30]
        assert rosout.records(node="chatty", level=30, match=lambda m: m == "hello from the learner") == []
        assert rosout.records(node="someone_else") == []
        assert "chatty" in rosout.loggers()
        assert wait_until(lambda: len(rosout.records(node="chatty", match=lambda m: m == "tick")) >= 2, 10.0)


SERVER = """
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.node import Node
    from rcl_interfaces.srv import ListParameters

    def answer(request, response):
        response.result.names = [p + "_seen" for p in request.prefixes]
        response.result.prefixes = [str(request.depth)]
        return response

    try:
        rclpy.init()
        node = Node("learner_server")
        srv = node.create_service(ListParameters, "echo_prefixes", answer)
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
"""


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_call_service_on_learner_server(ros_env, learners):
    from rcl_interfaces.srv import ListParameters  # noqa: PLC0415

    from ros2course.run.probes import RosSession, call_service  # noqa: PLC0415

    with RosSession() as session:
        proc = learners(session, "server", SERVER, ros_env)
        request = ListParameters.Request(prefixes=["alpha", "beta"], depth=7)
        response = call_service(session, ListParameters, "/echo_prefixes", request, timeout=15.0)
        assert list(response.result.names) == ["alpha_seen", "beta_seen"], describe(proc)
        assert list(response.result.prefixes) == ["7"]
        # a second call works too (the client is created and destroyed per call)
        again = call_service(session, ListParameters, "/echo_prefixes", ListParameters.Request(prefixes=["x"]))
        assert list(again.result.names) == ["x_seen"]
        with pytest.raises(TimeoutError):
            call_service(session, ListParameters, "/nobody_serves_this", ListParameters.Request(), timeout=1.0)


CLIENT = """
    import sys
    import rclpy
    from rclpy.node import Node
    from rcl_interfaces.srv import ListParameters

    rclpy.init()
    node = Node("learner_client")
    client = node.create_client(ListParameters, "grader_service")
    if not client.wait_for_service(timeout_sec=20.0):
        print("no service", flush=True)
        sys.exit(3)
    for i in range(3):
        future = client.call_async(ListParameters.Request(prefixes=[f"call{i}"], depth=i))
        rclpy.spin_until_future_complete(node, future, timeout_sec=10.0)
        print("answer", list(future.result().result.names), flush=True)
    node.destroy_node()
    rclpy.shutdown()
"""


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_stand_in_server_records_learner_calls(ros_env, learners):
    """The kit's one stand-in service server (DeferredServer) answers a learner's client and records its calls."""
    from rcl_interfaces.srv import ListParameters  # noqa: PLC0415

    from ros2course.kit.topics_services import DeferredServer  # noqa: PLC0415
    from ros2course.run.probes import RosSession  # noqa: PLC0415

    def handler(index, request, response):
        response.result.names = [f"grader{index}:" + p for p in request.prefixes]
        return response

    with RosSession() as session:
        server = DeferredServer(session, ListParameters, "/grader_service", handler)
        server.offer()
        try:
            proc = learners(session, "client", CLIENT, ros_env)
            assert wait_until(lambda: proc.poll() is not None, 30.0), describe(proc)
            assert proc.poll() == 0, describe(proc) + proc.stdout()
            assert [list(r.prefixes) for _, r in server.calls] == [["call0"], ["call1"], ["call2"]]
            assert [r.depth for _, r in server.calls] == [0, 1, 2]
            times = [t for t, _ in server.calls]
            assert times == sorted(times)
            assert server.rate() is not None and server.rate().samples == 2
            lines = [line for line in proc.stdout().splitlines() if line.startswith("answer")]
            assert lines == ["answer ['grader0:call0']", "answer ['grader1:call1']", "answer ['grader2:call2']"]
        finally:
            server.close()
        assert wait_until(lambda: "/grader_service" not in dict(session.node.get_service_names_and_types()), 5.0)


PARAM_NODE = """
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.node import Node

    try:
        rclpy.init()
        node = Node("param_node")
        node.declare_parameter("speed", 1.5)
        node.declare_parameter("label", "slow")
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
"""


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_parameter_client_lists_and_sets(ros_env, learners):
    from rclpy.parameter import Parameter  # noqa: PLC0415

    from ros2course.run.probes import RosSession, parameter_client, wait_future  # noqa: PLC0415

    with RosSession() as session:
        proc = learners(session, "params", PARAM_NODE, ros_env)
        with parameter_client(session, "/param_node", timeout=15.0) as client:
            listed = wait_future(client.list_parameters(), 5.0)
            assert {"speed", "label"} <= set(listed.result.names), describe(proc)
            got = wait_future(client.get_parameters(["speed", "label"]), 5.0)
            assert got.values[0].double_value == pytest.approx(1.5)
            assert got.values[1].string_value == "slow"
            done = wait_future(client.set_parameters([Parameter("speed", value=2.5)]), 5.0)
            assert [r.successful for r in done.results] == [True]
            got = wait_future(client.get_parameters(["speed"]), 5.0)
            assert got.values[0].double_value == pytest.approx(2.5)
            # a type change is refused by the node (declared double)
            refused = wait_future(client.set_parameters([Parameter("speed", value="fast")]), 5.0)
            assert [r.successful for r in refused.results] == [False]


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_parameter_client_times_out_without_node(ros_env):
    from ros2course.run.probes import RosSession, parameter_client  # noqa: PLC0415

    with RosSession() as session:
        with pytest.raises(TimeoutError):
            with parameter_client(session, "/no_such_node", timeout=1.0):
                pass


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_the_median_period_is_judged_when_asked():
    # a 500 Hz timer on a busy machine: most periods 2 ms, a few callbacks late and the periods they missed skipped
    deltas = [0.002] * 80 + [0.010, 0.0285, 0.006, 0.004] * 5
    times = [sum(deltas[:i]) for i in range(len(deltas) + 1)]
    stats = RateStats.from_times(times)
    assert stats.median_period == pytest.approx(0.002)
    assert not stats.within(500.0, 0.15)  # the mean: ~360 Hz
    assert stats.within(500.0, 0.15, median=True)
    assert not RateStats.from_times([i * 0.02 for i in range(50)]).within(500.0, 0.15, median=True)  # 50 Hz


def test_the_graders_fast_dds_profile_never_reaches_learner_nodes(tmp_path, monkeypatch):
    """The grader's participants announce every 0.25 s (probes.GRADER_ANNOUNCEMENT_PERIOD); learner nodes keep
    Fast DDS's defaults or the profile the user (or a batch job) set."""
    from xml.etree import ElementTree  # noqa: PLC0415

    from ros2course.run import probes  # noqa: PLC0415

    monkeypatch.setenv("ROS2COURSE_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("ROS2COURSE_DISCOVERY_RANGE", raising=False)
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")  # configure_process_discovery sets it: restored after
    monkeypatch.delenv(probes.PROFILES_VARIABLE, raising=False)
    monkeypatch.setattr(probes, "_profile_choice", probes._ProfileChoice())
    probes.configure_process_discovery()
    ours = os.environ[probes.PROFILES_VARIABLE]
    text = open(ours, encoding="utf-8").read()
    lease = ElementTree.fromstring(text).find(".//{*}leaseAnnouncement")
    assert (lease.findtext("{*}sec"), lease.findtext("{*}nanosec")) == ("0", "250000000")
    assert "useBuiltinTransports" not in text
    assert probes.PROFILES_VARIABLE not in probes.learner_profile_env(dict(os.environ))
    # a batch job's UDP-only profile: the grader's own is UDP only too, its learner nodes keep the job's file
    monkeypatch.setenv("ROS2COURSE_DISCOVERY_RANGE", "SUBNET")
    monkeypatch.setenv(probes.PROFILES_VARIABLE, "/job/fastdds-udp-only.xml")
    monkeypatch.setattr(probes, "_profile_choice", probes._ProfileChoice())
    probes.configure_process_discovery()
    assert open(os.environ[probes.PROFILES_VARIABLE], encoding="utf-8").read().count("ros2course_udp") == 2
    assert probes.learner_profile_env(dict(os.environ))[probes.PROFILES_VARIABLE] == "/job/fastdds-udp-only.xml"
    # a profile of the user's own is theirs: the grader leaves it alone
    monkeypatch.delenv("ROS2COURSE_DISCOVERY_RANGE")
    monkeypatch.setenv(probes.PROFILES_VARIABLE, "/home/me/my-dds.xml")
    monkeypatch.setattr(probes, "_profile_choice", probes._ProfileChoice())
    probes.configure_process_discovery()
    assert os.environ[probes.PROFILES_VARIABLE] == "/home/me/my-dds.xml"
    assert probes.learner_profile_env(dict(os.environ))[probes.PROFILES_VARIABLE] == "/home/me/my-dds.xml"
    # a cache folder it cannot write: Fast DDS's defaults, grading goes on
    monkeypatch.delenv(probes.PROFILES_VARIABLE)
    monkeypatch.setenv("ROS2COURSE_CACHE_DIR", str(tmp_path / "a-file" / "cache"))
    (tmp_path / "a-file").write_text("not a folder", encoding="utf-8")
    monkeypatch.setattr(probes, "_profile_choice", probes._ProfileChoice())
    probes.configure_process_discovery()
    assert probes.PROFILES_VARIABLE not in os.environ


def test_learner_env(ros_env):
    from ros2course.run.probes import RosSession  # noqa: PLC0415

    with RosSession() as session:
        env = session.learner_env({"ROS_LOCALHOST_ONLY": "1", "ROS_DOMAIN_ID": "0", "KEEP": "me"})
        assert env["ROS_DOMAIN_ID"] == str(session.domain_id)
        assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
        assert "ROS_LOCALHOST_ONLY" not in env
        assert env["KEEP"] == "me"
        assert env["PYTHONUNBUFFERED"] == "1"


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_parts_graded_at_once_share_one_check_graph(ros_env, tmp_path):
    """The part without a graph of its own and the part with one, started together (kit.parts.at_once):
    each thread's ``s.graph`` is fixed for the whole part, and the check has one ``s.ros``.

    Regression: ``s.graph`` of the own-graph part used to evaluate ``s.ros`` too, and two threads making
    ``s.ros`` at once made two graphs: the other part launched its node in one and looked for its
    services in the other ("serves: none" for a correct server, 5 of 12 runs of two checks at once).
    """
    import threading  # noqa: PLC0415
    import time  # noqa: PLC0415

    from ros2course.grade.checklist import Check  # noqa: PLC0415
    from ros2course.grade.session import GradingSession  # noqa: PLC0415
    from ros2course.kit import parts  # noqa: PLC0415
    from ros2course.lesson.catalog import load_catalog  # noqa: PLC0415

    lesson = load_catalog().get("service-server-client")
    for _ in range(5):
        s = GradingSession(lesson, [Check("a", "a", 1)], tmp_path, tmp_path / "log", ros_env)
        seen: dict[str, list] = {"shared": [], "own": []}
        both = threading.Barrier(2)

        def look(name: str) -> None:
            both.wait()  # the two parts touch the graph at the same moment
            for _ in range(3):
                seen[name].append(s.graph)
                time.sleep(0.01)

        try:
            parts.at_once(s, "shared", lambda: look("shared"), "own", lambda: look("own"), own_graphs={"own"})
        finally:
            s.close()
        assert all(graph is s.ros for graph in seen["shared"])
        assert len({id(graph) for graph in seen["own"]}) == 1 and seen["own"][0] is not s.ros


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_a_checks_domain_stays_reserved_until_its_processes_are_stopped(ros_env):
    """GradingSession closes its graphs before it stops its learner processes (a ros2 daemon among them):
    the domain id must stay reserved until the holder is closed, after them, or another check could take
    the domain and find the old daemon there ("already running", then gone: CI, inspect-topics)."""
    import contextlib
    import socket

    from ros2course.run.probes import RosSession  # noqa: PLC0415

    holder = contextlib.ExitStack()
    with RosSession(domain_holder=holder) as graph:
        domain = graph.domain_id
    port = 32768 + domain  # domain_coordinator's reservation: a bound port per domain id
    with socket.socket() as other, pytest.raises(OSError):
        other.bind(("", port))
    holder.close()
    with socket.socket() as other:
        other.bind(("", port))
