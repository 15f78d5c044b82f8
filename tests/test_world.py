"""The simulated Gazebo world of the gazebo-custom-nodes lesson (``ros2course.run.physics``, issue 40).

Without ROS: the physics (:class:`BoxWorld`: rest, Coulomb friction, one-step wrench impulses, set_state,
determinism) and Gazebo's entity rules. With ROS (marked ``ros``; each scenario in a child process with ROS's
environment, since tf2_ros' libraries must be found when the process starts): the world served in a private
graph, talked to by separate rclpy nodes as the learner's nodes would, and its lockstep with a P controller
on sim time like the author's.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys

import pytest

from ros2course.errors import MissingRequirement
from ros2course.run import physics as world_mod
from ros2course.run.physics import (
    BOX_ID,
    BOX_LINK_ID,
    GRAVITY,
    LINK,
    MODEL,
    NONE,
    STEP_SIZE,
    BoxWorld,
    pose_target,
    wrench_link,
)

#: The physics tests need MuJoCo (the ``gazebo`` extra, which CI installs).
needs_mujoco = pytest.mark.skipif(world_mod.mujoco is None, reason="mujoco not installed: pip install 'ros2course[gazebo]'")

G = GRAVITY  # m/s^2 (the SDF sets none: sdformat's 9.8)


def _run(world: BoxWorld, seconds: float, force: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> list:
    return [world.step(force) for _ in range(round(seconds / STEP_SIZE))]


@needs_mujoco
def test_the_box_at_rest_stays_at_half_a_metre_for_two_seconds():
    world = BoxWorld()
    steps = _run(world, 2.0)
    assert len(steps) == 500 and steps[-1].time == pytest.approx(2.0)
    assert all(abs(s.position[2] - 0.5) < 1e-3 for s in steps)
    assert all(abs(s.position[0]) < 1e-9 and abs(s.position[1]) < 1e-9 for s in steps)
    assert steps[-1].orientation == pytest.approx((0.0, 0.0, 0.0, 1.0), abs=1e-9)


@needs_mujoco
@pytest.mark.parametrize(("friction", "force"), [(1.0, 15.0), (1.0, 30.0), (0.5, 10.0)])
def test_a_force_above_friction_accelerates_the_box_as_f_minus_mu_m_g_predicts(friction, force):
    world = BoxWorld(friction=friction)
    steps = _run(world, 1.0, (force, 0.0, 0.0))
    measured = (steps[-1].linear_velocity[0] - steps[49].linear_velocity[0]) / (STEP_SIZE * (len(steps) - 50))
    predicted = (force - friction * 1.0 * G) / 1.0  # F - mu m g = m a, m = 1 kg
    assert measured == pytest.approx(predicted, rel=0.02)
    assert all(abs(s.position[2] - 0.5) < 1e-3 for s in steps)  # it slides, never hops nor tips
    assert steps[-1].force == (force, 0.0, 0.0)


@needs_mujoco
@pytest.mark.parametrize("force", [5.0, 9.5])
def test_a_force_below_static_friction_does_not_move_the_box(force):
    world = BoxWorld()  # static friction: mu m g = 9.8 N
    steps = _run(world, 2.0, (force, 0.0, 0.0))
    assert abs(steps[-1].position[0]) < 1e-4
    assert abs(steps[-1].linear_velocity[0]) < 1e-4


@needs_mujoco
def test_one_1000_newton_message_is_an_impulse_of_one_step():
    """ApplyLinkWrench applies a message for one step (0.004 s): 1000 N is 4 N s, less friction's 9.8 N
    for that step; then the box slides to rest, decelerated by mu g."""
    world = BoxWorld()
    pushed = world.step((1000.0, 0.0, 0.0))
    speed = (1000.0 - G) * STEP_SIZE  # m/s after the step: 3.9608
    assert pushed.linear_velocity[0] == pytest.approx(speed, rel=1e-3)
    after = _run(world, 2.0)
    travel = speed ** 2 / (2 * G) + speed * STEP_SIZE / 2  # the slide, and the step's own half-step term
    assert after[-1].position[0] == pytest.approx(travel, rel=0.01)
    assert after[-1].linear_velocity[0] == pytest.approx(0.0, abs=1e-6)
    assert max(s.position[2] for s in after) < 0.5 + 1e-3
    assert after[0].force == (0.0, 0.0, 0.0)


@needs_mujoco
def test_set_state_moves_the_box_and_zeroes_its_velocity():
    world = BoxWorld()
    _run(world, 0.5, (30.0, 0.0, 0.0))
    assert world.state().linear_velocity[0] > 5.0
    time_before = world.time
    world.set_state((1.0, 2.0, 0.5))
    state = world.state()
    assert state.position == pytest.approx((1.0, 2.0, 0.5), abs=1e-4)
    assert state.linear_velocity == (0.0, 0.0, 0.0) and state.angular_velocity == (0.0, 0.0, 0.0)
    assert state.time == time_before  # the time goes on
    steps = _run(world, 1.0)
    assert steps[-1].position == pytest.approx((1.0, 2.0, 0.5), abs=1e-4)
    world.set_state((0.0, 0.0, 3.0))  # dropped from 3 m: falls, lands, rests
    steps = _run(world, 2.0)
    assert steps[10].position[2] < 3.0 and steps[-1].position == pytest.approx((0.0, 0.0, 0.5), abs=1e-3)


def _scripted(world: BoxWorld) -> list:
    """A fixed script of inputs: pushes both ways, a set_state, a push along y and a torque."""
    out = [world.step((1000.0 if i == 3 else 20.0 * (i % 7) - 60.0, 0.0, 0.0)) for i in range(300)]
    world.set_state((0.5, -1.0, 0.5), (0.0, 0.0, 0.3826834, 0.9238795), (1.0, 0.0, 0.0))
    out += [world.step((0.0, 12.0, 0.0), (0.0, 0.0, 2.0 if i < 50 else 0.0)) for i in range(200)]
    return out


@needs_mujoco
def test_the_same_inputs_give_the_same_trajectory():
    first, second = BoxWorld(), BoxWorld()
    assert _scripted(first) == _scripted(second)
    third = BoxWorld()
    _run(third, 1.3, (25.0, 3.0, 0.0))  # a history of its own, then the same start
    third.set_state()
    trajectory = _scripted(third)
    assert [(s.position, s.orientation, s.linear_velocity) for s in trajectory] == \
        [(s.position, s.orientation, s.linear_velocity) for s in first.trajectory]


def test_entities_are_resolved_as_gazebo_resolves_them():
    # ApplyLinkWrench: the id when not 0 (the link 9, or the model 8 for its canonical link), else name and type
    assert wrench_link(9, "", NONE) == BOX_LINK_ID
    assert wrench_link(BOX_ID, "", NONE) == BOX_LINK_ID
    assert wrench_link(0, "box", NONE) is None  # the name alone is ignored (the author's remark)
    assert wrench_link(0, "box", MODEL) == BOX_LINK_ID
    assert wrench_link(0, "box_link", LINK) == BOX_LINK_ID and wrench_link(0, "box::box_link", LINK) == BOX_LINK_ID
    assert wrench_link(0, "box", LINK) is None
    assert wrench_link(10, "", NONE) is None  # a visual: neither a link nor a model
    assert wrench_link(4242, "box", MODEL) is None
    # UserCommands' set_pose: the id when not 0, else the world's child of that name (the type is not read)
    assert pose_target(0, "box") == BOX_ID and pose_target(BOX_ID, "") == BOX_ID
    assert pose_target(BOX_LINK_ID, "") == BOX_LINK_ID  # exists (success), but only a model moves
    assert pose_target(0, "box_link") is None and pose_target(0, "") is None and pose_target(0, "sphere") is None


def test_without_mujoco_the_world_says_what_installs_it(monkeypatch):
    monkeypatch.setattr(world_mod, "mujoco", None)
    with pytest.raises(MissingRequirement) as caught:
        BoxWorld()
    assert "mujoco" in caught.value.message and "\n" not in caught.value.message
    assert caught.value.hint == "pip install 'ros2course[gazebo]'"


# --- with ROS ----------------------------------------------------------------------------------------------

#: Set by .ci/run for the suite: the components CI builds must be there.
REQUIRE_VAR = "ROS2COURSE_REQUIRE_UNDERLAY"

#: Shared by both scenarios: a separate rclpy participant in the world's domain, spinning on a thread.
PRELUDE = r"""
import json, sys, threading, time
import rclpy, tf2_ros
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from ros2course.run.probes import RosSession, wait_until
from ros2course.run.physics import PhysicsWorld, load_types, WORLD

TYPES = load_types()
WRENCH, SET_POSE = f"/world/{WORLD}/wrench", f"/world/{WORLD}/set_pose"


class Peer:
    '''A node of its own (context, executor thread) in the world's domain, on sim time.'''

    def __init__(self, graph, name):
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=graph.domain_id)
        self.node = rclpy.create_node(name, context=self.context,
                                      parameter_overrides=[Parameter("use_sim_time", value=True)])
        self.buffer = tf2_ros.Buffer()
        self.listener = tf2_ros.TransformListener(self.buffer, self.node)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self.executor.spin, daemon=True)
        self.thread.start()

    def box(self):
        try:
            return self.buffer.lookup_transform(WORLD, "box", rclpy.time.Time())
        except tf2_ros.TransformException:
            return None

    def close(self):
        self.executor.shutdown()
        self.thread.join(5)
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)


def world_gone(graph, world):
    threads = [t.name for t in threading.enumerate() if t.name.startswith("ros2course-physics-world")]
    return not threads and wait_until(lambda: "_ros2course_physics_world" not in graph.node.get_node_names(), 5)
"""

SERVE = PRELUDE + r"""
out = {}
with RosSession() as graph:
    world = PhysicsWorld(graph, TYPES).start()
    strict = PhysicsWorld(graph, TYPES, world="strict", strict_set_pose=True).start(paused=True)
    peer = Peer(graph, "learner")
    client = peer.node.create_client(TYPES.set_entity_pose, SET_POSE)
    strict_client = peer.node.create_client(TYPES.set_entity_pose, "/world/strict/set_pose")
    assert client.wait_for_service(timeout_sec=10) and strict_client.wait_for_service(timeout_sec=10)

    def set_pose(cli, name, x, y):
        request = TYPES.set_entity_pose.Request()
        request.entity.name, request.pose.position.x, request.pose.position.y = name, x, y
        request.pose.position.z = 0.5
        future = cli.call_async(request)
        assert wait_until(future.done, 5)
        return future.result().success

    out["success"] = [set_pose(client, "box", 2.0, 1.0), set_pose(client, "nothing", 9.0, 9.0),
                      set_pose(strict_client, "box", 0.0, 0.0), set_pose(strict_client, "nothing", 9.0, 9.0)]
    wait_until(lambda: (t := peer.box()) is not None and abs(t.transform.translation.x - 2.0) < 1e-6, 5)
    seen = peer.box().transform.translation
    out["tf"] = [seen.x, seen.y, seen.z]
    out["records"] = [[r.target, r.applied, r.success] for r in world.set_pose_requests]
    # answer_delay: the pose is applied at once, the answer sent that long after (answered_at just before it)
    delayed = PhysicsWorld(graph, TYPES, world="delayed", answer_delay=0.5).start(paused=True)
    delayed_client = peer.node.create_client(TYPES.set_entity_pose, "/world/delayed/set_pose")
    assert delayed_client.wait_for_service(timeout_sec=10)
    asked = time.monotonic()
    assert set_pose(delayed_client, "box", 1.0, 0.0)
    got = time.monotonic()
    answered = delayed.set_pose_requests[0].answered_at
    out["delay"] = [answered - asked >= 0.5, got >= answered, delayed.box_state().position[0]]
    delayed.close()

    clocks = []
    peer.node.create_subscription(TYPES.clock, "/clock", lambda m: clocks.append(m.clock.sec + m.clock.nanosec * 1e-9), 10)
    publisher = peer.node.create_publisher(TYPES.entity_wrench, WRENCH, 1)
    assert wait_until(lambda: publisher.get_subscription_count() > 0 and len(clocks) > 10, 10)

    def push(entity_id, name, kind, force):
        msg = TYPES.entity_wrench()
        msg.entity.id, msg.entity.name, msg.entity.type, msg.wrench.force.x = entity_id, name, kind, force
        count = len(world.wrenches)
        publisher.publish(msg)
        assert wait_until(lambda: len(world.wrenches) > count and world.wrenches[-1].step is not None, 10)
        rested = world.wrenches[-1].step * 0.004 + 0.6  # sim seconds: the box slides to rest (0.8 m in 0.4 s)
        assert world.wait_for_sim_time(rested, 30)
        assert wait_until(lambda: (t := peer.box()).header.stamp.sec + t.header.stamp.nanosec * 1e-9 >= rested, 10)
        return peer.box().transform.translation.x

    out["x"] = [push(9, "", 0, 1000.0), push(0, "box", 0, -1000.0), push(0, "box", 2, -1000.0)]
    out["clock"] = [clocks[0], clocks[-1], all(b > a for a, b in zip(clocks, clocks[1:]))]
    # withhold_tf: the clock runs and no /tf goes out until it is set back
    withheld = PhysicsWorld(graph, TYPES, world="withheld", withhold_tf=True).start()
    poses = []
    peer.node.create_subscription(TYPES.tf_message, "/tf", lambda m: poses.extend(
        1 for t in m.transforms if t.header.frame_id == "withheld"), 100)
    assert wait_until(lambda: withheld.peers()[0] >= 2, 10)  # the peer's listener and this subscription
    start = withheld.sim_time
    assert withheld.wait_for_sim_time(start + 1.0, 10)
    out["withheld"] = [len(poses)]
    withheld.withhold_tf = False
    out["withheld"].append(wait_until(lambda: len(poses) > 0, 10))
    withheld.close()
    peer.close()
    world.close(); strict.close(); world.close()  # idempotent
    out["gone"] = world_gone(graph, world)
print(json.dumps(out))
"""

LOCKSTEP = PRELUDE + r"""
def controller(graph):
    '''The author's control_shape_thrust_node on sim time: every 1 ms (sim), a force of -5 (x + 3) N.'''
    peer = Peer(graph, "control_shape_thrust_node")
    publisher = peer.node.create_publisher(TYPES.entity_wrench, WRENCH, 1)

    def tick():
        seen = peer.box()
        if seen is not None:
            msg = TYPES.entity_wrench()
            msg.entity.id, msg.wrench.force.x = 9, -5.0 * (seen.transform.translation.x + 3.0)
            publisher.publish(msg)

    peer.node.create_timer(0.001, tick)
    return peer


def run(steps):
    with RosSession() as graph:
        world = PhysicsWorld(graph, TYPES, wait_for_input=0.5, real_time_factor=None).start()
        peer = controller(graph)
        assert world.wait_for_wrench(30), world.peers()  # the controller is live: start the check
        world.pause()
        world.wait_for_input = 10.0  # from now on a late answer (a loaded machine) only slows the run
        start = world.set_box_state()  # the SDF's start, at rest
        started = time.monotonic()
        world.resume()
        assert world.wait_for_sim_time((start + steps) * 0.004, 60)
        world.pause()
        wall = time.monotonic() - started
        trajectory = [s for s in world.trajectory if s.step >= start][:steps]
        peer.close()
        world.close()
        gone = world_gone(graph, world)
    return {"wall": wall, "gone": gone, "timeouts": sum(s.timed_out for s in trajectory),
            "trajectory": [[s.position[0], s.linear_velocity[0], s.force[0], s.inputs] for s in trajectory]}

print(json.dumps([run(300), run(300)]))
"""


@pytest.fixture
def ros_env() -> dict[str, str]:
    """The activated ROS environment with ros_gz_interfaces (the nav2 component); skips without it, or fails
    when ``ROS2COURSE_REQUIRE_UNDERLAY=1`` (CI builds it)."""
    from ros2course.ros import env as env_mod  # noqa: PLC0415

    env = env_mod.activate()
    index = ("share", "ament_index", "resource_index", "packages", "ros_gz_interfaces")
    if not any(os.path.isfile(os.path.join(p, *index)) for p in env.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p):
        why = "ros_gz_interfaces not installed: ros2course env --build --with nav2"
        if os.environ.get(REQUIRE_VAR) == "1":
            pytest.fail(f"{REQUIRE_VAR}=1 (CI) and {why}")
        pytest.skip(why)
    if shutil.which("colcon", path=env.get("PATH")) is None:
        pytest.skip("no ROS 2 install")
    return env


def _scenario(env: dict[str, str], script: str) -> object:
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=240,
                          stdin=subprocess.DEVNULL, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.ros
@pytest.mark.timeout(300)
def test_the_world_serves_set_pose_wrench_tf_and_clock(ros_env):
    out = _scenario(ros_env, SERVE)
    # the bridged /set_pose answers true whatever the entity; strict_set_pose answers as /set_pose/blocking
    assert out["success"] == [True, True, True, False]
    assert out["records"] == [[8, True, True], [None, False, True]]
    assert out["tf"] == pytest.approx([2.0, 1.0, 0.5], abs=1e-4)  # world -> box on /tf, on sim time
    assert out["delay"] == [True, True, 1.0]
    pushed, by_name_only, by_model_name = out["x"]
    assert pushed == pytest.approx(2.0 + 0.8086, abs=0.01)  # id 9, 1000 N for one step
    assert by_name_only == pushed  # a name without a type: Gazebo ignores it
    assert by_model_name == pytest.approx(pushed - 0.8086, abs=0.01)  # name "box" with type MODEL
    first, last, increasing = out["clock"]
    assert last > first + 1.0 and increasing
    assert out["withheld"] == [0, True]  # a second of sim time with no pose on /tf, then poses
    assert out["gone"]


@pytest.mark.ros
@pytest.mark.timeout(300)
def test_lockstep_with_a_controller_on_sim_time_gives_the_same_trajectory_twice(ros_env):
    first, second = _scenario(ros_env, LOCKSTEP)
    assert first["gone"] and second["gone"]
    assert first["timeouts"] == 0 and second["timeouts"] == 0
    assert len(first["trajectory"]) == 300
    assert first["trajectory"] == second["trajectory"]
    x = [step[0] for step in first["trajectory"]]
    assert first["trajectory"][0][3] == 0  # the first step from the new state takes no stale input
    assert all(step[3] == 1 for step in first["trajectory"][1:])  # then one answer per tick
    assert x[-1] < -1.0  # towards -3 (with mu = 1 it stops where |5 (x + 3)| < 9.8 N, after its momentum)
