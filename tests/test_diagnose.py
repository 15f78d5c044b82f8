"""The diagnosis of failed checks (issue 19): ros2course.run.diagnose and where it shows.

The graph tests build real rclpy nodes in one process, inside a
:class:`RosSession`'s context (private domain): a near-miss topic name, another
type, a BEST_EFFORT publisher against the grader's RELIABLE subscription,
duplicate node names, a correct graph. One engine test runs a real learner
process through :meth:`GradingSession.launch`.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import sys
import textwrap
from pathlib import Path

import pytest
from rich.console import Console

from ros2course.grade.results import CheckResult, LessonResult, Status
from ros2course.dev.validate import ExpectedDiagnosis, Fixture, judge_fixture
from ros2course.lesson.catalog import LessonGraph, load_catalog
from ros2course.report.table import render_result
from ros2course.run.diagnose import Diagnosis, clean, edit_distance, how_near, near_names

STRING = "std_msgs/msg/String"
CONTRACT = LessonGraph.validate({
    "nodes": [{"name": "/talker"}],
    "topics": [{"name": "/amazing_quote", "type": STRING, "role": "publish"}],
})


# --- names (no ROS) ------------------------------------------------------------------------

def test_edit_distance_and_how_near():
    assert edit_distance("/amazing_quote", "/amazing_quotes") == 1
    assert edit_distance("kitten", "sitting") == 3
    assert edit_distance("", "abc") == 3
    assert how_near("/amazing_quote", "/amazing_quotes") == "one character from /amazing_quote"
    assert how_near("/a_b", "/a_cd") == "2 characters from /a_b"
    assert how_near("/amazing_quote", "/ns/amazing_quote") == "the same name in namespace /ns, not /"


def test_near_names():
    assert near_names("/amazing_quote", ["/amazing_quotes", "/rosout", "/zzz"]) == ["/amazing_quotes"]
    assert near_names("/amazing_quote", ["/robot/amazing_quote"]) == ["/robot/amazing_quote"]
    assert near_names("/amazing_quote_subscriber_node", ["/quote_subscriber"]) == ["/quote_subscriber"]
    assert near_names("/amazing_quote", ["/amazing_quote", "/joint_states"]) == []


def test_clean_escapes_and_caps():
    assert clean("/a\x1b[31mb") == "/a\\x1b[31mb"
    long = clean("/" + "x" * 500)
    assert len(long) == 80 and long.endswith("…")


def test_lesson_graph_validates_names_and_parts():
    with pytest.raises(ValueError):
        LessonGraph.validate({"topics": [{"name": "amazing quote", "type": STRING}]})
    with pytest.raises(ValueError):
        LessonGraph.validate({"topics": [{"name": "/x", "type": "String"}]})
    graph = LessonGraph.validate({"nodes": [{"name": "/a", "part": "one"}, {"name": "/b", "part": "two"},
                                                  {"name": "/c"}]})
    assert [n.name for n in graph.for_part("one").nodes] == ["/a", "/c"]


def test_topics_and_services_share_one_endpoint_model():
    """One endpoint model for both lists; each list's roles and default role, and its kind of type."""
    graph = LessonGraph.validate({"topics": [{"name": "/t", "type": STRING}],
                                        "services": [{"name": "/s", "type": "std_srvs/srv/Trigger"}]})
    assert type(graph.topics[0]) is type(graph.services[0])
    assert (graph.topics[0].role, graph.services[0].role) == ("publish", "serve")
    assert graph.for_part("any").services[0].role == "serve"
    for wrong in ({"topics": [{"name": "/t", "type": STRING, "role": "serve"}]},
                  {"services": [{"name": "/s", "type": "std_srvs/srv/Trigger", "role": "subscribe"}]},
                  {"topics": [{"name": "/t", "type": "std_srvs/srv/Trigger"}]}):
        with pytest.raises(ValueError):
            LessonGraph.validate(wrong)


def test_declared_lessons_load():
    catalog = load_catalog()
    for lesson_id in ("print-forever-node", "publisher-subscriber", "service-server-client", "parameters",
                      "launch-files"):
        assert catalog.get(lesson_id).graph is not None, lesson_id


# --- the result model ---------------------------------------------------------------------

FINDING = Diagnosis("near_name", "node /p publishes /amazing_quotes (AmazingQuote), one character from /amazing_quote",
                    {"expected": "/amazing_quote", "found": "/amazing_quotes"})


def _result(passed: bool = False) -> LessonResult:
    check = CheckResult("pub_topic", "It publishes /amazing_quote", 0.0 if not passed else 2.0, 2.0, passed,
                        "publishes /amazing_quotes", "/amazing_quote", "" if passed else "spell it",
                        diagnosis=[] if passed else [FINDING])
    return LessonResult("publisher-subscriber", check.points, 2.0, Status.PASSED if passed else Status.FAILED,
                        [check])


def test_diagnosis_json_round_trip():
    result = _result()
    data = json.loads(json.dumps(result.to_record()))
    assert data["checks"][0]["diagnosis"] == [FINDING.to_dict()]
    again = LessonResult.from_record(data)
    assert again.checks[0].diagnosis == [FINDING]
    assert again.to_record() == result.to_record()


def test_no_diagnosis_keeps_the_documented_shape():
    assert "diagnosis" not in _result(passed=True).to_json()["checks"][0]
    plain = CheckResult("a", "A", 0.0, 1.0, False, "o", "e", "h")
    assert "diagnosis" not in plain.to_dict()
    assert CheckResult.from_dict(plain.to_dict()).diagnosis == []


def test_diagnosis_in_gradescope_and_table():
    result = _result()
    output = result.gradescope_tests(prefix=False)[0]["output"]
    assert output.splitlines()[-1] == f"why: {FINDING.message}"
    console = Console(file=io.StringIO(), width=200)
    render_result(result, console)
    assert f"why:      {FINDING.message}" in console.file.getvalue()


def test_judge_fixture_asserts_the_diagnosis():
    fixture = Fixture.model_validate({"description": "typo", "fails": ["pub_topic"],
                                      "diagnosis": [{"kind": "near_name", "mentions": ["/amazing_quotes"]}]})
    ok, expected = judge_fixture(fixture.fails, _result(), fixture.says, fixture.diagnosis)
    assert ok and "diagnosed: near_name" in expected
    wrong = [ExpectedDiagnosis(kind="qos", mentions=["RELIABLE"])]
    ok, expected = judge_fixture(fixture.fails, _result(), fixture.says, wrong)
    assert not ok and "missing: a qos diagnosis naming RELIABLE" in expected
    elsewhere = [ExpectedDiagnosis(kind="near_name", check="other_check")]
    assert not judge_fixture(fixture.fails, _result(), None, elsewhere)[0]


def _chained() -> LessonResult:
    """``node_name`` lost; ``rate`` needs it (not checked); ``log`` lost too; ``build`` passed."""
    return LessonResult("print-forever-node", 1.0, 10.0, Status.FAILED, [
        CheckResult("build", "It builds", 1.0, 1.0, True, "built", "", ""),
        CheckResult("node_name", "The node is named", 0.0, 3.0, False, "found /print_node", "/print_forever_node",
                    "name it print_forever_node"),
        CheckResult("rate", "It prints at 2 Hz", 0.0, 4.0, False, "not checked: 'The node is named' failed",
                    "(depends on the failed check above)", "use a 0.5 s timer", skipped=True),
        CheckResult("log", "It logs", 0.0, 2.0, False, "nothing logged", "a log line", "log it")])


def test_judge_fixture_fails_names_only_judged_checks():
    """A check not checked (a check it needs failed) proves nothing about itself: it goes under ``skips``."""
    ok, expected = judge_fixture(["node_name", "rate"], _chained())
    assert not ok
    assert "rate was not checked (a check it needs failed): list it under skips:" in expected
    ok, expected = judge_fixture(["node_name"], _chained(), skips=["rate"])
    assert ok, expected
    assert "not checked: rate" in expected
    assert judge_fixture(["node_name", "log"], _chained(), skips=["rate"])[0]


def test_judge_fixture_skips_must_be_not_checked():
    """Each check in ``skips`` must be present and not checked: a judged one (lost or passed) is not ok."""
    ok, expected = judge_fixture(["node_name"], _chained(), skips=["rate", "log"])
    assert not ok and "log was judged, not skipped: list it under fails:" in expected
    ok, expected = judge_fixture(["node_name"], _chained(), skips=["build"])
    assert not ok and "build was judged, not skipped: it kept its points" in expected
    ok, expected = judge_fixture(["node_name"], _chained(), skips=["nope"])
    assert not ok and "unknown check ids: nope" in expected
    broken = LessonResult("print-forever-node", 0.0, 10.0, Status.NOT_GRADABLE, [], "colcon build failed")
    assert judge_fixture(["build"], broken)[0]
    ok, expected = judge_fixture(["build"], broken, skips=["rate"])
    assert not ok and "never judged" in expected


def test_judge_fixture_keeps_says_with_skips():
    """``says:`` still applies beside ``skips`` (a not-checked check's feedback is its hint)."""
    assert judge_fixture(["node_name"], _chained(), {"node_name": ["print_node"]}, skips=["rate"])[0]
    ok, expected = judge_fixture(["node_name"], _chained(), {"node_name": ["talker"]}, skips=["rate"])
    assert not ok and "missing: node_name says 'talker'" in expected


def test_extra_lost_checks_are_a_note_not_a_failure():
    """Checks lost or not checked that the fixture names in neither list are reported by ``dev validate``."""
    from ros2course.dev.validate import Outcome, fixture_note  # noqa: PLC0415

    result = _chained()
    assert fixture_note(["node_name"], [], result) == "also lost: log; also not checked: rate"
    assert fixture_note(["node_name"], ["rate"], result) == "also lost: log"
    assert fixture_note(["node_name", "log"], ["rate"], result) == ""
    assert judge_fixture(["node_name"], result, skips=["rate"])[0]  # log lost too: still ok
    outcome = Outcome("print-forever-node", "wrong_name", True, "loses the points of node_name", "failed 1/10",
                      2.5, result, note=fixture_note(["node_name"], ["rate"], result))
    assert outcome.line() == "wrong_name: failed 1/10 (2.5 s); also lost: log"
    assert outcome.to_dict()["note"] == "also lost: log"
    assert "note" not in Outcome("l", "reference", True, "full marks", "passed", 1.0).to_dict()


# --- real graphs ----------------------------------------------------------------------------

@pytest.fixture
def graph():
    """A RosSession, and a function making extra rclpy nodes in its context (destroyed at the end)."""
    pytest.importorskip("rclpy")
    import rclpy  # noqa: PLC0415
    from rclpy.parameter import Parameter  # noqa: PLC0415

    from ros2course.ros import env as env_mod  # noqa: PLC0415
    from ros2course.run.probes import RosSession  # noqa: PLC0415

    env_mod.activate_process()
    made = []
    with RosSession() as session:
        def node(name: str, namespace: str | None = None):
            made.append(rclpy.create_node(name, namespace=namespace, context=session.context, enable_rosout=False,
                                          start_parameter_services=False,
                                          parameter_overrides=[Parameter("start_type_description_service",
                                                                         value=False)]))
            return made[-1]

        yield session, node
        for one in made:
            one.destroy_node()


def _kinds(findings: list[Diagnosis]) -> list[str]:
    return [d.kind for d in findings]


def _diagnose(session, contract: LessonGraph, **kwargs) -> list[Diagnosis]:
    """The engine's call: the graph observed once, QoS queried through the grader's node."""
    from ros2course.run.diagnose import diagnose, snapshot  # noqa: PLC0415

    return diagnose(snapshot(session), contract, ros_node=session.node, **kwargs)


def _settled(session, contract: LessonGraph, done) -> list[Diagnosis]:
    """Diagnose until ``done(findings)`` (in-process discovery takes a few ms), at most 10 s."""
    from ros2course.run.probes import wait_until  # noqa: PLC0415

    found: list[Diagnosis] = []

    def check() -> bool:
        found[:] = _diagnose(session, contract)
        return done(found)

    wait_until(check, 10.0, interval=0.05)
    return found


def _string():
    from std_msgs.msg import String  # noqa: PLC0415

    return String


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_near_miss_topic(graph):
    session, node = graph
    node("talker").create_publisher(_string(), "/amazing_quotes", 10)
    found = _settled(session, CONTRACT, lambda f: "near_name" in _kinds(f))
    assert _kinds(found) == ["no_peer", "near_name"], found
    assert "no node publishes the topic /amazing_quote" in found[0].message
    assert found[1].message == "node /talker publishes /amazing_quotes (String), one character from /amazing_quote"
    assert found[1].detail["found"] == "/amazing_quotes"


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_near_miss_node_and_namespace(graph):
    session, node = graph
    node("talkr").create_publisher(_string(), "/amazing_quote", 10)
    found = _settled(session, CONTRACT, lambda f: bool(f))
    assert _kinds(found) == ["near_name"] and "node /talkr is running, one character from /talker" in found[0].message
    node("talker", namespace="/robot").create_publisher(_string(), "/robot/amazing_quote", 10)
    found = _settled(session, CONTRACT, lambda f: any("/robot/talker" in d.message for d in f))
    assert any("the same name in namespace /robot, not /" in d.message for d in found), found


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_other_type(graph):
    from std_msgs.msg import Int32  # noqa: PLC0415

    session, node = graph
    node("talker").create_publisher(Int32, "/amazing_quote", 10)
    found = _settled(session, CONTRACT, lambda f: bool(f))
    assert _kinds(found) == ["other_type"], found
    assert found[0].message == ("node /talker publishes /amazing_quote as std_msgs/msg/Int32; "
                                "the lesson's type is std_msgs/msg/String")


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_best_effort_publisher_against_reliable_subscription(graph):
    from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: PLC0415

    session, node = graph
    node("talker").create_publisher(_string(), "/amazing_quote",
                                    QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
    session.topic("/amazing_quote", _string(), QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
    found = _settled(session, CONTRACT, lambda f: "qos" in _kinds(f))
    assert _kinds(found) == ["qos"], found
    message = found[0].message
    assert "the publisher of node /talker (BEST_EFFORT, VOLATILE)" in message
    assert "the subscription of the grader (RELIABLE, VOLATILE)" in message
    assert message.endswith("cannot connect: ERROR: Best effort publisher and reliable subscription"), message
    assert found[0].detail["publisher_qos"].startswith("BEST_EFFORT")


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_duplicate_node_names(graph):
    session, node = graph
    node("talker").create_publisher(_string(), "/amazing_quote", 10)
    node("talker")
    found = _settled(session, CONTRACT, lambda f: bool(f))
    assert _kinds(found) == ["duplicate_node"], found
    assert found[0].message.startswith("2 nodes in the graph are named /talker")


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_services(graph):
    from rcl_interfaces.srv import ListParameters  # noqa: PLC0415

    session, node = graph
    contract = LessonGraph.validate({"services": [{"name": "/what_is_the_point",
                                                         "type": "rcl_interfaces/srv/ListParameters"}]})
    node("server").create_service(ListParameters, "/what_is_the_pont", lambda request, response: response)
    found = _settled(session, contract, lambda f: "near_name" in _kinds(f))
    assert _kinds(found) == ["no_peer", "near_name"], found
    assert "node /server serves /what_is_the_pont (ListParameters), one character from /what_is_the_point" in found[1].message


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_correct_graph_has_no_diagnosis(graph):
    from ros2course.run.probes import wait_until  # noqa: PLC0415

    session, node = graph
    node("talker").create_publisher(_string(), "/amazing_quote", 10)
    session.topic("/amazing_quote", _string(), 10)
    assert wait_until(lambda: "/amazing_quote" in session.topic_types() and "/talker" in session.node_names(), 10.0)
    assert _diagnose(session, CONTRACT) == []
    assert _diagnose(session, LessonGraph()) == []


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_an_empty_graph_and_a_broken_query_say_nothing(graph):
    from ros2course.run.diagnose import diagnose, snapshot  # noqa: PLC0415

    session, _ = graph
    assert _diagnose(session, CONTRACT) == []  # no learner node, no process: nothing to say

    class Broken:
        node = None

    assert diagnose(snapshot(Broken()), CONTRACT, ros_node=None) == []


LEARNER = """
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from std_msgs.msg import String

    try:
        rclpy.init()
        node = rclpy.create_node("amazing_quote_publisher_node")
        node.create_publisher(String, "/amazing_quotes", 1)
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
"""


@pytest.mark.ros
@pytest.mark.timeout(90)
@pytest.mark.parametrize("diagnose", ["1", "0"])
def test_engine_diagnoses_the_first_failed_check_of_a_part(tmp_path, monkeypatch, diagnose):
    """GradingSession.record attaches the diagnosis once per part, in the graph the part launched into;
    with ROS2COURSE_DIAGNOSE=0 there is none, and every verdict and point is the same."""
    monkeypatch.setenv("ROS2COURSE_DIAGNOSE", diagnose)
    pytest.importorskip("rclpy")
    from ros2course.grade.checklist import Check  # noqa: PLC0415
    from ros2course.grade.session import GradingSession  # noqa: PLC0415
    from ros2course.ros import env as env_mod  # noqa: PLC0415
    from ros2course.run.probes import wait_until  # noqa: PLC0415

    lesson = dataclasses.replace(load_catalog().get("publisher-subscriber"), graph=LessonGraph.validate({
        "nodes": [{"name": "/amazing_quote_publisher_node", "part": "publisher"}],
        "topics": [{"name": "/amazing_quote", "type": STRING, "part": "publisher"}]}))
    (tmp_path / "install").mkdir()
    (tmp_path / "install" / "setup.bash").write_text("", encoding="utf-8")
    script = tmp_path / "learner.py"
    script.write_text(textwrap.dedent(LEARNER), encoding="utf-8")
    env = env_mod.activate()
    checks = [Check("before", "before any launch", 1, part="publisher"),
              Check("topic", "the topic", 1, part="publisher"), Check("later", "later", 1, part="publisher")]
    s = GradingSession(lesson, checks, tmp_path, tmp_path / "log", env)
    try:
        with s.part("publisher"):
            s.record("before", False, "nothing launched yet", "-")
            s.launch(Path(sys.executable), "learner", [str(script)])
            # the node's own endpoints, as the grader's kit waits for them (ros2 node info)
            assert wait_until(lambda: "/amazing_quote_publisher_node" in s.ros.node_names() and any(
                name == "/amazing_quotes" for name, _ in s.ros.node.get_publisher_names_and_types_by_node(
                    "amazing_quote_publisher_node", "/")), 20.0)
            s.record("topic", False, "no message on /amazing_quote", "messages on /amazing_quote")
            s.record("later", False, "still nothing", "-")
    finally:
        s.close()
    results = s.results
    assert [(r.id, r.passed, r.points) for r in results.values()] == [
        ("before", False, 0.0), ("topic", False, 0.0), ("later", False, 0.0)]  # the verdicts are the grader's
    if diagnose == "0":
        assert all(r.diagnosis == [] for r in results.values()) and not s.diagnose_seconds
        return
    assert results["before"].diagnosis == []  # no graph watched yet
    assert [d.kind for d in results["topic"].diagnosis] == ["no_peer", "near_name"]
    assert "/amazing_quotes (String), one character from /amazing_quote" in results["topic"].diagnosis[1].message
    assert results["later"].diagnosis == []  # once per part
    assert results["topic"].points == 0.0 and not results["topic"].passed  # the verdict is the grader's
    assert len(s.diagnose_seconds) == 1 and "diagnose" in s.timings
    # the observed side of `ros2course graph`: one snapshot for the part, taken at its first verdict after the launch
    import json  # noqa: PLC0415

    saved = json.loads((tmp_path / "log" / "graph.json").read_text(encoding="utf-8"))
    assert [p["part"] for p in saved["parts"]] == ["publisher"]
    assert "/amazing_quote_publisher_node" in saved["parts"][0]["nodes"]
    assert saved["parts"][0]["ends"]["publish"]["/amazing_quotes"] == {"/amazing_quote_publisher_node": [STRING]}
    print(f"diagnosis took {s.diagnose_seconds[0] * 1000:.1f} ms")


def test_diagnosis_in_the_html_report_is_escaped(tmp_path):
    pytest.importorskip("jinja2")
    from ros2course.report.html import render_report  # noqa: PLC0415

    result = _result()
    result.student = "s1"
    result.checks[0].diagnosis = [Diagnosis("near_name", "node /x publishes /<script>alert(1)</script>", {})]
    (tmp_path / "results.jsonl").write_text(json.dumps(result.to_record()) + "\n", encoding="utf-8")
    html = render_report(tmp_path, similarity=False)
    assert "why: node /x publishes /&lt;script&gt;alert(1)&lt;/script&gt;" in html
    assert "<script>alert(1)" not in html


# --- the learner's process and a silent publisher (issue 19, engine-made, real processes) -------------

CRASHER = """
    import os, signal, sys, time
    import rclpy

    rclpy.init()
    node = rclpy.create_node("crasher")
    time.sleep(0.3)
    how = sys.argv[1]
    if how == "raise":
        raise RuntimeError("the robot is on fire")
    if how == "error":
        node.get_logger().error("cannot open /dev/ttyUSB0")
        node.get_logger().info("giving up")
        sys.exit(3)
    os.kill(os.getpid(), signal.SIGSEGV)
"""

TALKER = """
    import sys, time
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from std_msgs.msg import String

    try:
        rclpy.init()
        node = rclpy.create_node("talker")
        publisher = node.create_publisher(String, "/amazing_quote", 10)
        node.create_timer(0.1, lambda: publisher.publish(String(data="Use the force, Pikachu!")))
        if sys.argv[1] == "spins":
            rclpy.spin(node)
        else:
            while rclpy.ok():  # waits for Ctrl+C but never spins: the timer never fires
                time.sleep(0.05)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
"""


def _session(tmp_path, checks, graph: LessonGraph | None):
    from ros2course.grade.session import GradingSession  # noqa: PLC0415
    from ros2course.ros import env as env_mod  # noqa: PLC0415

    lesson = dataclasses.replace(load_catalog().get("publisher-subscriber"), graph=graph)
    (tmp_path / "install").mkdir(exist_ok=True)
    (tmp_path / "install" / "setup.bash").write_text("", encoding="utf-8")
    env = env_mod.activate()
    return GradingSession(lesson, checks, tmp_path, tmp_path / "log", env)


@pytest.mark.ros
@pytest.mark.timeout(120)
@pytest.mark.parametrize("how, words", [
    ("raise", ["exited with code 1 after", "RuntimeError: the robot is on fire"]),
    ("error", ["exited with code 3 after", "[ERROR]", "[crasher]: cannot open /dev/ttyUSB0"]),
    ("segv", ["was killed by SIGSEGV after"]),
])
def test_a_learner_process_that_ends_is_diagnosed(tmp_path, how, words):
    """A node that dies on its own: the engine's ``process`` finding says how (code or signal, seconds
    after start) and why (last traceback line, else last ERROR record); kit.process_state says the same."""
    pytest.importorskip("rclpy")
    from ros2course.grade.checklist import Check  # noqa: PLC0415
    from ros2course.kit import process_state  # noqa: PLC0415
    from ros2course.run.probes import wait_until  # noqa: PLC0415

    script = tmp_path / "crasher.py"
    script.write_text(textwrap.dedent(CRASHER), encoding="utf-8")
    s = _session(tmp_path, [Check("node", "the node runs", 1)], None)  # no graph: process findings still come
    try:
        with s.part():
            proc = s.launch(Path(sys.executable), "crasher", [str(script), how])
            assert wait_until(lambda: proc.poll() is not None, 30.0)
            state = process_state(proc)
            s.record("node", False, f"no node; {state}", "a node that keeps running")
    finally:
        s.close()
    findings = s.results["node"].diagnosis
    assert [d.kind for d in findings] == ["process"], findings
    for word in words:
        assert findings[0].mentions(word), (word, findings[0].message)
        assert word in state, (word, state)  # one account of the process: observed text and diagnosis agree
    seconds = float(findings[0].detail["seconds"])
    assert seconds >= 0.3  # it slept 0.3 s before dying: the time is measured from start, not from the verdict
    assert findings[0].message.startswith("the learner's process crasher ")


@pytest.mark.ros
@pytest.mark.timeout(120)
def test_a_node_stopped_by_the_grader_is_not_a_process_finding(tmp_path):
    """Ctrl+C from the grader ends the process: that exit is not the learner's crash."""
    pytest.importorskip("rclpy")
    from ros2course.grade.checklist import Check  # noqa: PLC0415
    from ros2course.run.probes import wait_until  # noqa: PLC0415

    script = tmp_path / "talker.py"
    script.write_text(textwrap.dedent(TALKER), encoding="utf-8")
    s = _session(tmp_path, [Check("sigint", "Ctrl+C", 1)], None)
    try:
        with s.part():
            proc = s.launch(Path(sys.executable), "talker", [str(script), "spins"])
            assert wait_until(lambda: "/talker" in s.ros.node_names(), 30.0)
            assert proc.interrupt()
            assert wait_until(lambda: proc.poll() is not None, 10.0)
            s.record("sigint", False, "exit code 0 but too late (a grader's own verdict)", "-")
    finally:
        s.close()
    assert s.results["sigint"].diagnosis == []


SCRIPT = """#!/usr/bin/python3
# EASY-INSTALL-ENTRY-SCRIPT: '{dist}','console_scripts','{name}'
import re
import sys

__requires__ = '{dist}'
from importlib.metadata import distribution


def importlib_load_entry_point(spec, group, name):
    dist_name, _, _ = spec.partition('==')
    matches = (
        entry_point
        for entry_point in distribution(dist_name).entry_points
        if entry_point.group == group and entry_point.name == name
    )
    return next(matches).load()


globals().setdefault('load_entry_point', importlib_load_entry_point)


if __name__ == '__main__':
    sys.argv[0] = re.sub(r'(-script\\.pyw?|\\.exe)?$', '', sys.argv[0])
    sys.exit(load_entry_point('{dist}', 'console_scripts', '{name}')())
"""


def _installed(root: Path, package: str, version: str, scripts: list[str]) -> Path:
    """``install/<package>`` as colcon's ament_python build leaves it: a console script written the way
    setuptools writes it, and ``<package>-<version>-py3.X.egg-info`` listing ``scripts``."""
    site = root / "install" / package / "lib" / f"python3.{sys.version_info.minor}" / "site-packages"
    info = site / f"{package}-{version}-py3.{sys.version_info.minor}.egg-info"
    info.mkdir(parents=True, exist_ok=True)
    (info / "PKG-INFO").write_text(f"Metadata-Version: 2.1\nName: {package}\nVersion: {version}\n", encoding="utf-8")
    (info / "entry_points.txt").write_text(
        "[console_scripts]\n" + "".join(f"{s} = {package}.{s}:main\n" for s in scripts), encoding="utf-8")
    script = root / "install" / package / "lib" / package / "print_forever_node"
    script.parent.mkdir(parents=True, exist_ok=True)
    script.write_text(SCRIPT.format(dist=f"{package}==0.0.1", name="print_forever_node"), encoding="utf-8")
    script.chmod(0o755)
    return script


def test_an_entry_point_missing_from_the_installed_metadata(tmp_path):
    """The issue's stale install: the script's entry point is not in the metadata importlib.metadata finds,
    so the console script dies in next(matches) (StopIteration): said with the metadata's name."""
    import subprocess  # noqa: PLC0415

    from ros2course.run.diagnose import missing_entry_point, process_findings  # noqa: PLC0415
    from ros2course.run.process import LearnerProcess  # noqa: PLC0415

    package = "python_package_with_a_node"
    script = _installed(tmp_path, package, "0.0.1", ["some_other_node"])
    site = next((tmp_path / "install" / package / "lib").glob("python3*/site-packages"))
    env = {**os.environ, "PYTHONPATH": str(site)}
    run = subprocess.run([sys.executable, str(script)], env=env, capture_output=True, text=True, timeout=60,
                         check=False)
    assert run.returncode == 1 and "StopIteration" in run.stderr  # what the learner sees
    found = missing_entry_point(script)
    assert found is not None and found.kind == "process"
    assert found.mentions("print_forever_node") and found.mentions(f"{package}-0.0.1-py3.{sys.version_info.minor}.egg-info")
    assert found.detail["console_scripts"] == "some_other_node"
    # the same through a learner process that ran it: its exit, then the missing entry point
    proc = LearnerProcess([sys.executable, str(script)], env, tmp_path / "log", "print_forever_node")
    proc.program = script  # the console script (run through the interpreter here)
    proc.start()
    proc.popen.wait(timeout=60)
    proc.stop()
    kinds = [(d.kind, d.detail.get("program", "")) for d in process_findings([proc])]
    assert kinds == [("process", ""), ("process", "print_forever_node")], kinds
    # a correct install says nothing
    fixed = _installed(tmp_path / "ok", package, "0.0.1", ["print_forever_node"])
    assert missing_entry_point(fixed) is None
    assert missing_entry_point(Path(sys.executable)) is None  # not a console script


@pytest.mark.ros
@pytest.mark.timeout(120)
@pytest.mark.parametrize("spins", [False, True])
def test_a_node_that_never_spins_is_silent(tmp_path, spins):
    """A node whose publisher the grader's subscription matched, that never published: ``silent``. The same
    node spinning (its messages arrive) gets no such finding: never a false cause."""
    pytest.importorskip("rclpy")
    from std_msgs.msg import String  # noqa: PLC0415

    from ros2course.grade.checklist import Check  # noqa: PLC0415
    from ros2course.run.diagnose import SILENT_AFTER  # noqa: PLC0415
    from ros2course.run.probes import wait_until  # noqa: PLC0415

    contract = LessonGraph.validate({"nodes": [{"name": "/talker"}],
                                           "topics": [{"name": "/amazing_quote", "type": STRING}]})
    script = tmp_path / "talker.py"
    script.write_text(textwrap.dedent(TALKER), encoding="utf-8")
    s = _session(tmp_path, [Check("node", "the node", 1), Check("messages", "messages", 1)], contract)
    try:
        with s.part():
            probe = s.ros.topic("/amazing_quote", String)
            s.launch(Path(sys.executable), "talker", [str(script), "spins" if spins else "never"])
            assert wait_until(lambda: any(not i.node_name.startswith("_") for i in
                                          s.ros.node.get_publishers_info_by_topic("/amazing_quote")), 30.0)
            s.record("node", True, "/talker", "/talker")  # the engine sees the match from here on
            probe.wait_for_count(3, SILENT_AFTER + 1.0)  # the grader's observation window
            s.record("messages", False, f"{len(probe.messages())} message(s)", "messages on /amazing_quote")
    finally:
        s.close()
    findings = s.results["messages"].diagnosis
    if spins:
        assert probe.messages() and "silent" not in [d.kind for d in findings], findings
        return
    assert [d.kind for d in findings] == ["silent"], findings
    assert findings[0].mentions("/talker") and findings[0].mentions("/amazing_quote")


@pytest.mark.ros
@pytest.mark.timeout(90)
def test_a_part_opened_with_its_own_graph_gives_it_to_every_step_inside(tmp_path):
    """``s.part(name, own_graph=True)``: ``s.graph`` and ``s.launch`` use the part's private graph (issue 23:
    no ``graph=`` threaded through the steps); outside it, and in a part without one, ``s.graph`` is ``s.ros``."""
    from ros2course.grade.checklist import Check  # noqa: PLC0415
    from ros2course.run.probes import wait_until  # noqa: PLC0415

    script = tmp_path / "learner.py"
    script.write_text(textwrap.dedent(LEARNER), encoding="utf-8")
    s = _session(tmp_path, [Check("topic", "the topic", 1, part="own")], None)
    try:
        assert s.graph is s.ros
        with s.part("own", own_graph=True):
            own = s.graph
            assert own is not s.ros and own.domain_id != s.ros.domain_id
            with s.part("inner"):  # a nested part without a graph of its own observes the enclosing one's
                assert s.graph is own
            s.launch(Path(sys.executable), "learner", [str(script)])
            assert wait_until(lambda: "/amazing_quote_publisher_node" in own.node_names(), 20.0)
            assert "/amazing_quote_publisher_node" not in s.ros.node_names()
        assert s.graph is s.ros
    finally:
        s.close()
