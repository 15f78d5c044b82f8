"""graders/_qos.py: the qos lesson's compatibility verdicts agree with what DDS really matches.

The grader judges "a RELIABLE subscription never matches this publisher" and
"a TRANSIENT_LOCAL late joiner can match it" from the graph's endpoint
information and ``rclpy.qos.qos_check_compatible`` (through
``_qos.compatible``), not from waiting for messages that do not come. This
test holds that verdict against the real thing: a publisher of a known profile
runs in its own process in a private domain, the grader's session subscribes
with several profiles, and each subscription ends in one of two events, a
match (``get_publisher_count() == 1``) or rmw's incompatible-QoS event
(``SubscriptionEventCallbacks(incompatible_qos=...)``). ``_qos.compatible``
must predict which, both for the offered profile as the graph reports it
and for the same profile as made in code (``_qos.as_reported``).
"""

from __future__ import annotations

import sys
import textwrap
import threading

import pytest

PY = sys.executable

PUBLISHER = """
    import sys
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String

    reliable, transient_local = sys.argv[1] == "reliable", sys.argv[2] == "transient_local"
    qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                     reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL if transient_local else DurabilityPolicy.VOLATILE)
    try:
        rclpy.init()
        node = rclpy.create_node("known_qos_publisher")
        node.create_publisher(String, "/qos_under_test", qos)
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
"""

#: (reliable, transient_local) of the grader's subscriptions: every combination.
REQUESTS = [(False, False), (True, False), (True, True), (False, True)]


def _lesson_module(name: str):
    """A module of the course's graders folder (a helper of one lesson lives with its grader)."""
    import importlib

    from ros2course.grade.engine import graders_package

    return importlib.import_module(f"{graders_package()}.{name}")


@pytest.fixture
def ros_env():
    pytest.importorskip("rclpy")
    from ros2course.ros import env as env_mod

    env = env_mod.activate()
    return env


@pytest.mark.ros
@pytest.mark.timeout(120)
@pytest.mark.parametrize(("reliable", "transient_local"), [(False, False), (True, True), (True, False)],
                         ids=["sensor_data", "latched", "plain_depth"])
def test_compatible_predicts_what_dds_matches(ros_env, tmp_path, reliable, transient_local):
    from rclpy.event_handler import SubscriptionEventCallbacks
    from ros2course.run.probes import RosSession, wait_until
    from ros2course.run.process import LearnerProcess, sweep_stale_fastdds_shm
    from std_msgs.msg import String

    _qos = _lesson_module("_qos")
    script = tmp_path / "known_qos_publisher.py"
    script.write_text(textwrap.dedent(PUBLISHER), encoding="utf-8")
    args = ["reliable" if reliable else "best_effort", "transient_local" if transient_local else "volatile"]
    made_in_code = _qos.profile(reliable=reliable, transient_local=transient_local, depth=1)
    with RosSession() as session:
        proc = LearnerProcess([PY, str(script), *args], session.learner_env(ros_env), tmp_path / "logs",
                              "publisher", ros_sigint=True)
        incompatible = {request: threading.Event() for request in REQUESTS}
        subscriptions = {}
        try:
            proc.start()
            for request in REQUESTS:
                callbacks = SubscriptionEventCallbacks(
                    incompatible_qos=lambda _status, r=request: incompatible[r].set())
                subscriptions[request] = session.node.create_subscription(
                    String, "/qos_under_test", lambda _msg: None,
                    _qos.profile(reliable=request[0], transient_local=request[1], depth=10),
                    event_callbacks=callbacks)

            def settled() -> bool:  # every subscription either matched or was told it cannot
                return all(subscriptions[r].get_publisher_count() > 0 or incompatible[r].is_set() for r in REQUESTS)

            assert wait_until(settled, 30.0, abort=lambda: proc.poll() is not None), \
                f"not every subscription settled: exit {proc.poll()}; {proc.stderr()[-1500:]}"
            offered = _qos.wait_endpoint_qos(session, "/qos_under_test", "known_qos_publisher", "publishers")
            assert len(offered) == 1
            assert _qos.describe(offered[0]) == _qos.describe(made_in_code)
            for request in REQUESTS:
                matched = subscriptions[request].get_publisher_count() > 0
                assert matched != incompatible[request].is_set(), request
                requested = subscriptions[request].qos_profile
                from_graph, reason = _qos.compatible(offered[0], requested)
                from_code, _ = _qos.compatible(made_in_code, requested)
                assert from_graph == matched, f"offered {_qos.describe(offered[0])}, requested {request}: {reason}"
                assert from_code == matched, f"offered {_qos.describe(made_in_code)} (made in code), requested {request}"
        finally:
            proc.stop(sigint_timeout=3.0, sigterm_timeout=2.0)
    sweep_stale_fastdds_shm()
