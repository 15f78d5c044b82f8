"""A physics world on MuJoCo that serves what the Gazebo world of the ``gazebo-custom-nodes`` lesson serves (issue 40).

The lesson (the Jazzy edition of Murilo Marinho's ROS 2 tutorial, chapter gazebo/custom_nodes) has the
learner write three nodes that talk to the Gazebo world ``shapes_with_tf2_and_wrench``
(``gazebo_tutorial_workspace/scenes/shapes_with_tf2_and_wrench.sdf``) through ``ros_gz_bridge``. Gazebo does
not install here, so the grader runs this world instead: its box on its ground plane, simulated by MuJoCo,
and the ROS endpoints the bridge would give the learner's nodes:

* the service ``/world/<world>/set_pose`` (``ros_gz_interfaces/srv/SetEntityPose``; gz-sim's UserCommands),
* the topic ``/world/<world>/wrench`` (``ros_gz_interfaces/msg/EntityWrench``; gz-sim's ApplyLinkWrench),
* ``/tf`` (``tf2_msgs/msg/TFMessage``): the box's pose, parent frame ``<world>``, child ``box`` (gz-sim's
  PosePublisher on the model, bridged from ``/model/box/pose``),
* ``/clock`` (``rosgraph_msgs/msg/Clock``; gz-sim's SimulationRunner), so that nodes run with
  ``use_sim_time:=true`` live on the world's time.

Two layers: :class:`BoxWorld` is the physics alone (no ROS: the unit tests drive it), and :class:`PhysicsWorld`
serves it in a grading session's ROS graph from a stepping thread.

What is emulated, and where each rule comes from (gz-sim, the files named; read, not copied):

* Entity ids (:data:`ENTITIES`): gz-sim numbers entities in creation order: the world (1,
  ``SimulationRunner::CreateEntities``), the default level (2, ``LevelManager::ConfigureDefaultLevel``), the wind
  (3, ``SdfEntityCreator::CreateEntities(sdf::World)``), then each model in SDF order with its links and, per
  link, its visuals then its collisions (``SdfEntityCreator::CreateEntities(sdf::Model)``/``(sdf::Link)``):
  ground_plane 4 (link 5), box 8 and its link ``box_link`` 9, the id the author's nodes send.
* set_pose (``src/systems/user_commands/UserCommands.cc``, ``updatePose``): the entity is ``entity.id`` when it
  is not 0, else the world's child named ``entity.name``; its type is not read. Only a model moves
  (``src/systems/physics/Physics.cc``, ``Each<Model, WorldPoseCmd>``), never one with a plane collision (the
  ground) nor with a non-finite pose or a zero quaternion. The answer: ros_gz_bridge calls the gz service of the
  ROS service's name and answers its Boolean as ``success`` (ros_gz ``ros_gz_bridge/src/service_factory.hpp``),
  here the asynchronous ``/set_pose``, whose handler (``UserCommandsPrivate::ServiceHandler``) answers true as
  soon as it queued the command, whatever the entity: ``success`` is always true here too unless ``strict_set_pose``
  asks for what ``/set_pose/blocking`` answers (whether the entity exists). The pose is applied before the
  next step, as Physics applies a WorldPoseCmd before it steps. gz-physics' dartsim plugin keeps the box's
  velocity (``FreeGroupFeatures::SetFreeGroupWorldPose`` only sets the free joint's transform); this world
  zeroes it unless ``keep_velocity_on_set_pose``.
* wrench (``src/systems/apply_link_wrench/ApplyLinkWrench.cc``): every message received is queued
  (``OnWrench``) and the queue is emptied at the next unpaused step (``PreUpdate``; while paused the messages
  wait). The entity: ``entityFromMsg`` (``src/Util.cc``): ``entity.id`` when not 0, else ``entity.name`` (a
  scoped name such as ``box::box_link`` or its end) among entities of ``entity.type``, and nothing when the
  type is NONE: the name alone is ignored, as the author says. A model stands for its canonical link
  (``decomposeMessage``); anything else is an error Gazebo logs and skips. Each message adds its force and
  torque to the link's ``ExternalWorldWrenchCmd`` (``Link::AddWorldWrench``, ``src/Link.cc``: summed, world
  frame, at the link origin, here the centre of mass), which Physics applies for that one step and then clears.
  So a single 1000 N message on the 1 kg box lasts one 0.004 s step: an impulse of 4 N s.
* ``/tf`` at every step: the PosePublisher (``src/systems/pose_publisher/PosePublisher.cc``) of the SDF sets no
  ``update_frequency``, so its period is 0 and it publishes in every ``PostUpdate``; with
  ``publish_nested_model_pose`` true, ``publish_model_pose`` defaults to it and the model's pose is published
  with frame_id the world's name and child_frame_id ``box``, stamped with the sim time of that step.
* ``/clock`` at every step (``SimulationRunner::PublishStats``: the clock message is not throttled).
* Pace: one 0.004 s step (``max_step_size``) every 0.004 s / real-time factor of wall time; a late step is not
  caught up (``SimulationRunner::Run``: the next update is ``now + period`` once behind).

The physics (:class:`BoxWorld`): ground plane, the box (1 kg, 1 m cube, inertia 0.16666 kg m^2 about each axis,
start pose 0 0 0.5), time step 0.004 s, gravity 9.8 m/s^2 down (the SDF sets none: sdformat's default
``0 0 -9.8``, ``sdf/1.11/world.sdf``), Coulomb friction coefficient 1 (see :data:`FRICTION`).

Units throughout: seconds, metres, newtons, newton-metres, radians; quaternions are ``(x, y, z, w)`` as ROS
writes them. ROS modules are imported inside the functions that use them; ``mujoco`` at module level, and a
missing ``mujoco`` is reported by :class:`BoxWorld` (:class:`~ros2course.errors.MissingRequirement`).
"""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

from ros2course.errors import MissingRequirement
from ros2course.run.probes import record, spin_until_shutdown, stop_spinning

# The world renders nothing: without an OpenGL backend, importing mujoco loads none (with the default, its
# glfw probe starts a Python subprocess at import and evals what it prints, which failed under pdoc). Only set
# when unset: a process that renders (MUJOCO_GL=egl) keeps its choice.
os.environ.setdefault("MUJOCO_GL", "disable")
try:
    import mujoco
    import numpy
except ImportError:  # the gazebo extra is not installed: BoxWorld says so
    mujoco = numpy = None

#: The world's name (the SDF's ``<world name>``): topic and service prefix, and the parent frame on /tf.
WORLD = "shapes_with_tf2_and_wrench"
#: Seconds of sim time per step (the SDF's ``max_step_size``), and the same in nanoseconds (stamps).
STEP_SIZE = 0.004
STEP_NS = 4_000_000
#: m/s^2, pointing down: sdformat's default gravity (the SDF sets none).
GRAVITY = 9.8
#: Coulomb friction coefficient between the box and the ground. The SDF gives neither collision a
#: ``<surface>``, so both take sdformat's defaults, ``<ode><mu>`` 1 and ``<mu2>`` 1 (``sdf/1.11/surface.sdf``).
#: ODE (the SDF's ``type="ode"``) and gz-physics' dartsim plugin (what gz-sim's Physics loads by default,
#: ``src/systems/physics/Physics.cc``) both combine two surfaces' coefficients, and any combination of 1 and 1 is 1.
FRICTION = 1.0
#: The box: name (model and child frame), kg, metres (cube edge), kg m^2 (each principal moment), start position.
BOX = "box"
BOX_MASS = 1.0
BOX_SIZE = 1.0
BOX_INERTIA = 0.16666
BOX_START = (0.0, 0.0, 0.5)
#: What installs MuJoCo (the hint of the error a missing ``mujoco`` raises).
INSTALL_HINT = "pip install 'ros2course[gazebo]'"

#: ``ros_gz_interfaces/msg/Entity`` types (the same numbers as ``gz.msgs.Entity.Type``).
NONE, LIGHT, MODEL, LINK, VISUAL, COLLISION, SENSOR, JOINT = range(8)
#: Entity ids of the modelled part of the world (see the module docstring): id -> (name, type, parent id).
#: The SDF's other shapes (cylinder, sphere, capsule, ellipsoid, cone) and its light are not modelled.
ENTITIES: dict[int, tuple[str, int, int]] = {
    1: (WORLD, NONE, 0), 2: ("", NONE, 1), 3: ("", NONE, 1),
    4: ("ground_plane", MODEL, 1), 5: ("link", LINK, 4), 6: ("visual", VISUAL, 5), 7: ("collision", COLLISION, 5),
    8: (BOX, MODEL, 1), 9: ("box_link", LINK, 8), 10: ("box_visual", VISUAL, 9), 11: ("box_collision", COLLISION, 9),
}
WORLD_ID, GROUND_ID, BOX_ID, BOX_LINK_ID = 1, 4, 8, 9
#: A model's canonical link (its first link, gz-sim's ``Model::CanonicalLink``).
CANONICAL_LINK = {4: 5, 8: 9}

#: Seconds of sim time the box settles on the ground when the world is made (see :meth:`BoxWorld.__init__`).
SETTLE_TIME = 0.5
#: Metres: a box set this close to its resting height, upright and still, is set at exactly that height.
REST_SNAP = 1e-4
#: The mean distance (metres) of a 1 m square's points from its centre, (sqrt 2 + ln(1 + sqrt 2)) / 6: the
#: lever of the torsional friction of a box resting on one face.
TORSION_LEVER = (math.sqrt(2.0) + math.log(1.0 + math.sqrt(2.0))) / 6.0

Vector = tuple[float, float, float]
Quaternion = tuple[float, float, float, float]


# --- entities ----------------------------------------------------------------------------------------------

def scoped_name(entity_id: int) -> str:
    """``box::box_link`` for 9: the names from the world's child down, joined by ``::`` (gz-sim's ``scopedName``)."""
    names = []
    while entity_id in ENTITIES and entity_id != WORLD_ID:
        name, _, entity_id = ENTITIES[entity_id]
        names.append(name)
    return "::".join(reversed(names))


def pose_target(entity_id: int, name: str) -> int | None:
    """The entity a set_pose request names, as gz-sim's UserCommands ``updatePose`` finds it, or None.

    Args:
        entity_id: ``entity.id`` of the request; used when it is not 0.
        name: ``entity.name``; otherwise the world's direct child of that name (``entity.type`` is not read).

    Returns:
        an id of :data:`ENTITIES` (not necessarily one that moves: only :data:`BOX_ID` does), or None when
        there is no such entity (Gazebo's "Unable to update the pose").
    """
    if entity_id != 0:
        return entity_id if entity_id in ENTITIES else None
    children = [i for i, (n, _, parent) in ENTITIES.items() if parent == WORLD_ID and n and n == name]
    return children[0] if name and children else None


def wrench_link(entity_id: int, name: str, kind: int) -> int | None:
    """The link a wrench message is applied to, as gz-sim's ApplyLinkWrench finds it, or None (ignored).

    ``entityFromMsg`` (gz-sim ``src/Util.cc``): ``entity_id`` when it is not 0; else, when ``kind`` is not
    NONE, the entity of that type whose scoped name is ``name`` or ends with ``::name``. Then
    ``decomposeMessage`` (``ApplyLinkWrench.cc``): a link is itself, a model its canonical link, anything else
    is skipped.

    Args:
        entity_id: ``entity.id`` of the message.
        name: ``entity.name``.
        kind: ``entity.type`` (:data:`MODEL`, :data:`LINK`, ...).
    """
    if entity_id == 0:
        if kind == NONE or not name:
            return None
        found = [i for i, (_, t, _) in ENTITIES.items() if t == kind
                 and (scoped_name(i) == name or scoped_name(i).endswith("::" + name))]
        entity_id = found[0] if found else 0
    if entity_id not in ENTITIES:
        return None
    kind = ENTITIES[entity_id][1]
    return entity_id if kind == LINK else CANONICAL_LINK.get(entity_id) if kind == MODEL else None


# --- physics -----------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class BoxState:
    """The box at one instant.

    Attributes:
        time: sim seconds since the world started.
        position: metres, world frame (the box's centre).
        orientation: unit quaternion ``(x, y, z, w)``, world frame.
        linear_velocity: m/s, world frame.
        angular_velocity: rad/s, world frame.
    """

    time: float
    position: Vector
    orientation: Quaternion
    linear_velocity: Vector
    angular_velocity: Vector


@dataclass(frozen=True)
class StepRecord:
    """One step of the world: its input and the box after it.

    Attributes:
        step: 1 for the first step after the world was made.
        time: sim seconds at the end of the step (the stamp of the /tf and /clock published after it).
        position: metres; orientation: ``(x, y, z, w)``; linear_velocity: m/s (the box after the step).
        force: newtons, world frame, applied to the box during this step (the sum of its wrench messages).
        torque: newton-metres, world frame, likewise.
        inputs: wrench messages taken by this step (ignored ones included: unknown entity, not the box).
        timed_out: lockstep only (``wait_for_input``): no wrench arrived after the previous publication
            within the wait, and the world stepped without one.
    """

    step: int
    time: float
    position: Vector
    orientation: Quaternion
    linear_velocity: Vector
    force: Vector
    torque: Vector
    inputs: int = 0
    timed_out: bool = False


def _require_mujoco() -> None:
    if mujoco is None:
        raise MissingRequirement("the simulated Gazebo world needs the MuJoCo physics engine (Python package "
                                 "mujoco), which is not installed", INSTALL_HINT)


def model_xml(gravity: float = GRAVITY) -> str:
    """The MJCF of the world: the SDF's ground plane and box, and MuJoCo's contact settings.

    The contacts are frictionless (``condim`` 1): :class:`BoxWorld` applies the friction itself. Contact
    softness: ``solref`` 0.008 s (twice the step, MuJoCo's stiffest stable time constant) and ``solimp``
    0.99 (the box rests 1e-5 m into the ground); ``noslip_iterations`` makes static friction hold without creep.

    Args:
        gravity: m/s^2, pointing down.
    """
    half = BOX_SIZE / 2
    return f"""<mujoco model="{WORLD}">
  <option timestep="{STEP_SIZE}" gravity="0 0 {-gravity}" noslip_iterations="10"/>
  <default><geom condim="1" solref="{2 * STEP_SIZE} 1" solimp="0.99 0.99 0.001"/></default>
  <worldbody>
    <geom name="ground_plane" type="plane" size="50 50 1"/>
    <body name="{BOX}" pos="{' '.join(map(str, BOX_START))}">
      <freejoint name="{BOX}"/>
      <inertial pos="0 0 0" mass="{BOX_MASS}" diaginertia="{BOX_INERTIA} {BOX_INERTIA} {BOX_INERTIA}"/>
      <geom name="box_collision" type="box" size="{half} {half} {half}"/>
    </body>
  </worldbody>
</mujoco>"""


class BoxWorld:
    """The physics of the world (no ROS): the box on the ground plane, stepped 0.004 s at a time by MuJoCo.

    Friction: Coulomb, coefficient ``friction``, bounded by ``friction`` times the ground's normal force on the
    box in the previous step (MuJoCo's ``frictionloss`` on the box's horizontal degrees of freedom, and on its
    yaw with the lever :data:`TORSION_LEVER`), acting at the centre of mass. It is not MuJoCo's contact friction
    on purpose: a 1 m cube with a coefficient of 1 is exactly at its tipping limit whenever it slides (friction's
    moment about the centre of mass equals the normal force's at the front edge), where MuJoCo's soft contacts
    tip it over and make it hop; a 1000 N push on contact friction loses half its impulse to the contact.
    Acting at the centre of mass, friction never tips the box, and the box slides as a rigid box with Coulomb
    friction does: ``m a = F - mu N`` while sliding, at rest while ``|F| <= mu N``.

    The same initial state and the same per-step inputs give the same trajectory: MuJoCo is deterministic on
    one machine, every :meth:`set_state` starts the solver afresh, and nothing else is read.

    Args:
        friction: the friction coefficient (:data:`FRICTION`).
        gravity: m/s^2, pointing down (:data:`GRAVITY`).

    Attributes:
        trajectory: one :class:`StepRecord` per step, oldest first.
        rest_height: metres: the height at which the box rests on the ground (0.5 less the contact's
            compression, about 1e-5 m).

    Raises:
        MissingRequirement: the ``mujoco`` package is not installed (hint: :data:`INSTALL_HINT`).
    """

    def __init__(self, friction: float = FRICTION, gravity: float = GRAVITY) -> None:
        _require_mujoco()
        self.friction = friction
        self.model = mujoco.MjModel.from_xml_string(model_xml(gravity))
        self.data = mujoco.MjData(self.model)
        self._body = self.model.body(BOX).id
        self._ground = self.model.geom("ground_plane").id
        self.steps = 0
        self.trajectory: list[StepRecord] = []
        self._normal = 0.0
        self.rest_height = math.inf
        self.rest_height = self._settle()
        self.set_state()

    def _settle(self) -> float:
        """Let the box settle at its start pose for :data:`SETTLE_TIME` (unrecorded); its height then."""
        self.set_state(snap=False)
        for _ in range(round(SETTLE_TIME / STEP_SIZE)):
            self._advance((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        return float(self.data.qpos[2])

    @property
    def time(self) -> float:
        """Sim seconds since the world was made (settling excluded)."""
        return self.steps * STEP_SIZE

    @property
    def time_ns(self) -> int:
        """Sim nanoseconds since the world was made (exact: the stamps of /clock and /tf)."""
        return self.steps * STEP_NS

    def state(self) -> BoxState:
        """The box now (:class:`BoxState`)."""
        q, v = self.data.qpos, self.data.qvel
        return BoxState(self.time, _vec(q[0:3]), _ros_quaternion(q[3:7]), _vec(v[0:3]), self._angular_world())

    def _angular_world(self) -> Vector:
        """rad/s in the world frame (MuJoCo keeps a free joint's angular velocity in the body frame)."""
        return _vec(_rotation(self.data.qpos[3:7]) @ self.data.qvel[3:6])

    def set_state(self, position: Sequence[float] = BOX_START, orientation: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
                  linear_velocity: Sequence[float] = (0.0, 0.0, 0.0),
                  angular_velocity: Sequence[float] = (0.0, 0.0, 0.0), snap: bool = True) -> None:
        """Put the box at ``position`` (metres) with ``orientation`` (``(x, y, z, w)``, normalised here) and
        velocities (m/s, rad/s; world frame); the time goes on. Defaults: the SDF's start, at rest.

        An upright box set still within :data:`REST_SNAP` of its resting height is set at exactly that height,
        so that it starts in equilibrium with the ground (it does at the SDF's 0.5 m). The solver starts afresh
        (``mj_resetData``): what happened before never changes what follows.

        Args:
            snap: False sets the height as given (used while settling).
        """
        quaternion = _mujoco_quaternion(orientation)
        position = list(position)
        still = not any(linear_velocity) and not any(angular_velocity)
        if snap and still and _upright(quaternion) and abs(position[2] - self.rest_height) <= REST_SNAP:
            position[2] = self.rest_height
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[0:3], self.data.qpos[3:7] = position, quaternion
        self.data.qvel[0:3] = linear_velocity
        self.data.qvel[3:6] = _rotation(quaternion).T @ numpy.asarray(angular_velocity, dtype=float)
        mujoco.mj_forward(self.model, self.data)
        self._normal = self._ground_normal_force()

    def step(self, force: Sequence[float] = (0.0, 0.0, 0.0), torque: Sequence[float] = (0.0, 0.0, 0.0),
             inputs: int = 0, timed_out: bool = False) -> StepRecord:
        """Advance 0.004 s with ``force`` (N) and ``torque`` (N m), world frame, at the centre of mass, during
        this step only; record it.

        Args:
            inputs: how many wrench messages gave the force (recorded, see :class:`StepRecord`).
            timed_out: recorded (lockstep: no input arrived in time).

        Returns:
            the :class:`StepRecord` appended to :attr:`trajectory`.
        """
        self._advance(force, torque)
        self.steps += 1
        state = self.state()
        entry = StepRecord(self.steps, state.time, state.position, state.orientation, state.linear_velocity,
                           _vec(force), _vec(torque), inputs, timed_out)
        self.trajectory.append(entry)
        return entry

    def _advance(self, force: Sequence[float], torque: Sequence[float]) -> None:
        """One MuJoCo step with the wrench applied and the friction bounded by the last normal force."""
        bound = self.friction * self._normal
        self.model.dof_frictionloss[0:2] = bound
        self.model.dof_frictionloss[5] = bound * TORSION_LEVER
        self.data.xfrc_applied[self._body] = [*force, *torque]
        mujoco.mj_step(self.model, self.data)
        self.data.xfrc_applied[self._body] = 0.0
        self._normal = self._ground_normal_force()

    def _ground_normal_force(self) -> float:
        """Newtons: the sum of the normal forces of the ground's contacts with the box (0 in the air)."""
        total, buffer = 0.0, numpy.zeros(6)
        for index in range(self.data.ncon):
            contact = self.data.contact[index]
            if self._ground in (contact.geom1, contact.geom2):
                mujoco.mj_contactForce(self.model, self.data, index, buffer)
                total += float(buffer[0])
        return total


def _vec(values: Sequence[float]) -> Vector:
    return (float(values[0]), float(values[1]), float(values[2]))


def _rotation(wxyz: Sequence[float]) -> Any:
    """The 3x3 rotation matrix (numpy) of MuJoCo's quaternion ``(w, x, y, z)``."""
    matrix = numpy.zeros(9)
    mujoco.mju_quat2Mat(matrix, numpy.asarray(wxyz, dtype=float))
    return matrix.reshape(3, 3)


def _upright(wxyz: Sequence[float]) -> bool:
    """Whether the rotation is about the vertical only (the box rests on its bottom face)."""
    return wxyz[1] ** 2 + wxyz[2] ** 2 < 1e-12


def _ros_quaternion(wxyz: Sequence[float]) -> Quaternion:
    """MuJoCo's ``(w, x, y, z)`` as ROS's ``(x, y, z, w)``."""
    return (float(wxyz[1]), float(wxyz[2]), float(wxyz[3]), float(wxyz[0]))


def _mujoco_quaternion(xyzw: Sequence[float]) -> list[float]:
    """ROS's ``(x, y, z, w)``, normalised, as MuJoCo's ``(w, x, y, z)``.

    Raises:
        ValueError: not finite, or of length 0.
    """
    x, y, z, w = (float(v) for v in xyzw)
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not math.isfinite(norm) or norm == 0.0:
        raise ValueError(f"not a rotation: quaternion {tuple(xyzw)}")
    return [w / norm, x / norm, y / norm, z / norm]


# --- ROS -----------------------------------------------------------------------------------------------------

class WorldTypes(NamedTuple):
    """The message and service classes the world serves (from the ROS install, never a workspace)."""

    set_entity_pose: type  # ros_gz_interfaces/srv/SetEntityPose
    entity_wrench: type  # ros_gz_interfaces/msg/EntityWrench
    tf_message: type  # tf2_msgs/msg/TFMessage
    clock: type  # rosgraph_msgs/msg/Clock


def load_types(env: dict[str, str] | None = None) -> WorldTypes:
    """The classes of :class:`WorldTypes`, loaded as a grading session's ``installed_type`` loads them
    (:func:`ros2course.ros.interfaces.workspace_type`: ros_gz_interfaces from the optional nav2 component,
    tf2_msgs from the underlay; rosgraph_msgs is a wheel).

    Args:
        env: the ROS install's environment (a grading session's ``base_env``); default: this process's
            environment, activated (:func:`ros2course.ros.env.activate`).

    Raises:
        NotGradable: ros_gz_interfaces (or tf2_msgs) is not installed or does not load; the hint says how to
            build it.
    """
    from ros2course.ros import env as env_mod  # noqa: PLC0415 - ROS only when a world is served
    from ros2course.ros.interfaces import component_type, workspace_type  # noqa: PLC0415 - ROS only when a world is served

    if env is None:
        env = env_mod.activate()
    needed_by = "the simulated Gazebo world"
    set_pose = component_type(env, "ros_gz_interfaces", "srv", "SetEntityPose", needed_by=needed_by)
    wrench = component_type(env, "ros_gz_interfaces", "msg", "EntityWrench", needed_by=needed_by)
    tf_message = workspace_type(env, "tf2_msgs", "msg", "TFMessage")  # the underlay's (tf2), never optional
    from rosgraph_msgs.msg import Clock  # noqa: PLC0415 - ROS only when a world is served

    return WorldTypes(set_pose, wrench, tf_message, Clock)


@dataclass
class SetPoseRecord:
    """One set_pose request the world answered.

    Attributes:
        wall_time: ``time.time()`` seconds when it arrived.
        sim_time: sim seconds then (the box is moved before the next step).
        entity: ``(id, name, type)`` of the request's ``entity``.
        target: the entity id it named (:func:`pose_target`), None for no entity.
        position: metres; orientation: ``(x, y, z, w)`` as requested.
        applied: the box was moved (the target was the box model and the pose valid).
        success: the ``success`` answered.
        answered_at: ``time.monotonic()`` seconds just before the answer was sent (None until then): a
            client that ends before it did not wait for its answer.
    """

    wall_time: float
    sim_time: float
    entity: tuple[int, str, int]
    target: int | None
    position: Vector
    orientation: Quaternion
    applied: bool
    success: bool
    answered_at: float | None = None


@dataclass
class WrenchRecord:
    """One wrench message the world received.

    Attributes:
        wall_time: ``time.time()`` seconds when it arrived.
        sim_time: sim seconds then (of the last step published).
        entity: ``(id, name, type)`` of the message's ``entity``.
        link: the link it applies to (:func:`wrench_link`), None when Gazebo would skip it.
        force: newtons; torque: newton-metres (world frame, as sent).
        step: the :class:`StepRecord` step that took it (None while queued, or when dropped).
        dropped: computed before :meth:`PhysicsWorld.set_box_state` moved the box, so never applied.
    """

    wall_time: float
    sim_time: float
    entity: tuple[int, str, int]
    link: int | None
    force: Vector
    torque: Vector
    step: int | None = None
    dropped: bool = False

    @property
    def applied(self) -> bool:
        """Whether it pushes the box (its link is the box's)."""
        return self.link == BOX_LINK_ID


#: The world's node (hidden: ``RosSession.node_names`` leaves out names starting with ``_``).
NODE_NAME = "_ros2course_physics_world"


class PhysicsWorld:
    """:class:`BoxWorld` served in a ROS graph as Gazebo and ros_gz_bridge serve the author's world (module
    docstring): ``/world/<world>/set_pose``, ``/world/<world>/wrench``, ``/tf`` and ``/clock``.

    Like :class:`ros2course.kit.actions.StandInActionServer` it lives on a node and an executor of its
    own, in the graph's rclpy context, and nothing of it is in the graph before :meth:`start`. A stepping thread
    advances the physics one 0.004 s step at a time, at ``real_time_factor`` (None: as fast as it can), and
    after each step publishes the box's pose on /tf, then the time on /clock (in this order: a node on sim time
    whose timer fires on the new clock then finds the new pose in its buffer). :meth:`close` ends everything.

    Lockstep (``wait_for_input``): "a loaded machine slows the run but never changes the physics the grader
    judges". After publishing a step, the world waits up to ``wait_for_input`` wall seconds for a wrench message
    received after that publication, then steps with every message received so far; at the timeout it steps
    without one and records ``timed_out``. A controller on sim time that answers each /clock tick therefore gets
    exactly one step per answer whatever the load: its trajectory depends on its answers only. The real-time
    factor still bounds the pace from above. While the controller starts, steps time out (the box rests): a
    check waits for its first answer (:meth:`wait_for_wrench`), pauses, sets the box's state
    (:meth:`set_box_state`, which drops the answers computed before) and judges the steps from there; two such
    runs give the same trajectory to the last bit (tests/test_world.py).

    Args:
        graph: the :class:`~ros2course.run.probes.RosSession` to serve in (its ``context``; the world records
            the set_pose requests and answers and the wrench messages in the graph's recording).
        types: the classes (:func:`load_types`; default: loaded from this process's ROS install).
        world: the world's name (topics, service, /tf parent frame).
        friction: Coulomb coefficient (:data:`FRICTION`); gravity: m/s^2 down (:data:`GRAVITY`).
        real_time_factor: sim seconds per wall second; None or 0 for no pacing.
        wait_for_input: lockstep wait in wall seconds, or None (no lockstep).
        strict_set_pose: answer ``success`` false for an unknown entity (Gazebo's ``/set_pose/blocking``);
            default: true for every request, as the bridged ``/set_pose`` answers.
        keep_velocity_on_set_pose: keep the box's velocity when set_pose moves it (gz-physics' dartsim does);
            default: the box is set at rest.
        answer_delay: wall seconds between a set_pose request and its answer (the pose is applied at once).
            gz-sim answers a bridged request only after the simulation's next update, so a client gets its
            answer some time after asking; a delay makes a client that ends without waiting for the answer
            end before it (:attr:`SetPoseRecord.answered_at`). Other callbacks of the world wait meanwhile.
        withhold_tf: publish /clock only, no /tf, while this attribute is True (settable at any time): a world
            whose clock runs before the box's pose reaches the controller (in Gazebo: the bridge of the pose
            not up yet, or the PosePublisher's first message still on its way), so a controller's "no
            transform yet" branch runs on purpose.

    Attributes:
        physics: the :class:`BoxWorld` (read it under :attr:`lock`, or through :meth:`box_state`).
        set_pose_requests: a :class:`SetPoseRecord` per request, oldest first.
        wrenches: a :class:`WrenchRecord` per message, oldest first.
        lock: the ``threading.Condition`` guarding the physics and the records.

    Raises:
        MissingRequirement: MuJoCo is not installed.
        NotGradable: the Gazebo interfaces do not load (only when ``types`` is not given).
    """

    def __init__(self, graph: Any, types: WorldTypes | None = None, *, world: str = WORLD,
                 friction: float = FRICTION, gravity: float = GRAVITY, real_time_factor: float | None = 1.0,
                 wait_for_input: float | None = None, strict_set_pose: bool = False,
                 keep_velocity_on_set_pose: bool = False, answer_delay: float = 0.0,
                 withhold_tf: bool = False) -> None:
        self.physics = BoxWorld(friction, gravity)
        self.withhold_tf = withhold_tf
        self.types = types or load_types()
        self.graph, self.world = graph, world
        self.real_time_factor, self.wait_for_input = real_time_factor, wait_for_input
        self.strict_set_pose, self.keep_velocity_on_set_pose = strict_set_pose, keep_velocity_on_set_pose
        self.answer_delay = answer_delay
        self.set_pose_service = f"/world/{world}/set_pose"
        self.wrench_topic = f"/world/{world}/wrench"
        self.set_pose_requests: list[SetPoseRecord] = []
        self.wrenches: list[WrenchRecord] = []
        self.lock = threading.Condition()
        self._queued: list[WrenchRecord] = []
        self._fresh = False  # a wrench arrived since the last publication
        self._published = 0
        self._paused = self._closing = False
        self._restarted = False  # set_box_state: drop inputs until the next publication
        self._stale_answer = False  # ... and wait for the answer to the publication before it (lockstep)
        self._node = self._executor = self._spinner = self._stepper = None

    # --- life cycle ---

    def start(self, paused: bool = False) -> PhysicsWorld:
        """Create the node and its endpoints (they appear in the graph), spin them, and start stepping
        (or not yet: ``paused``; see :meth:`resume`, :meth:`step`). Returns the world."""
        self._paused = paused
        self._make_node()
        self._stepper = threading.Thread(target=self._run, daemon=True, name="ros2course-physics-world")
        self._stepper.start()
        return self

    def _make_node(self) -> None:
        import rclpy  # noqa: PLC0415 - ROS only when a world is served
        from rclpy.executors import SingleThreadedExecutor  # noqa: PLC0415 - ROS only when a world is served
        from rclpy.parameter import Parameter  # noqa: PLC0415 - ROS only when a world is served
        from rclpy.qos import QoSProfile  # noqa: PLC0415 - ROS only when a world is served

        self._node = node = rclpy.create_node(
            NODE_NAME, context=self.graph.context, enable_rosout=False, start_parameter_services=False,
            parameter_overrides=[Parameter("start_type_description_service", value=False)])
        # /tf as tf2_ros' listeners want it (reliable, depth 100); the wrench subscription deep enough for bursts
        self._tf_pub = node.create_publisher(self.types.tf_message, "/tf", QoSProfile(depth=100))
        self._clock_pub = node.create_publisher(self.types.clock, "/clock", 10)
        node.create_subscription(self.types.entity_wrench, self.wrench_topic, self._on_wrench, 100)
        node.create_service(self.types.set_entity_pose, self.set_pose_service, self._on_set_pose)
        # One thread: the callbacks are short. A MultiThreadedExecutor here spun a core at 100 % (the node's
        # default callback group is mutually exclusive: while one callback runs in the pool, rclpy's
        # MultiThreadedExecutor._spin_once_impl finds the other ready entities again at once and loops), and a
        # lockstep step took 60 ms instead of 2.1 ms with a controller in another process (measured here).
        self._executor = SingleThreadedExecutor(context=self.graph.context)
        self._executor.add_node(node)
        self._spinner = threading.Thread(target=spin_until_shutdown, args=(self._executor,), daemon=True,
                                         name="ros2course-physics-world-executor")
        self._spinner.start()

    def close(self) -> None:
        """Stop stepping (joins the thread), stop spinning, destroy the endpoints and the node. Idempotent;
        nothing to do before :meth:`start`."""
        with self.lock:
            self._closing = True
            self.lock.notify_all()
        stepped = self._stepper is None or self._stepper is threading.current_thread()
        if not stepped:
            self._stepper.join(10.0)
            stepped = not self._stepper.is_alive()
        spun = self._spinner is None or stop_spinning(self._executor, self._spinner)
        # A node destroyed while a thread may still publish on it or wait in the executor on it crashes the
        # process (see stop_spinning); a thread that has not left keeps its node (a daemon thread: a leak of
        # this grading process, never a crash), and the graph's context shutdown ends it.
        if self._node is not None and stepped and spun:
            self._node.destroy_node()  # its publishers, subscription and service with it
        self._node = self._executor = self._spinner = self._stepper = None

    def __enter__(self) -> PhysicsWorld:
        return self.start()

    def __exit__(self, *exc: Any) -> None:
        self.close()

    # --- control ---

    def pause(self) -> None:
        """Stop stepping after the current step (wrench messages wait in the queue, as in Gazebo)."""
        with self.lock:
            self._paused = True
            self.lock.notify_all()

    def resume(self) -> None:
        """Step again at the real-time factor."""
        with self.lock:
            self._paused = False
            self.lock.notify_all()

    @property
    def paused(self) -> bool:
        """Whether the stepping thread is paused."""
        return self._paused

    def step(self, count: int = 1) -> list[StepRecord]:
        """Advance ``count`` steps now, on the calling thread, publishing each (lockstep waits included, no
        pacing); only while paused.

        Raises:
            RuntimeError: the world is running (pause it first), or not started.
        """
        if not self._paused or self._node is None:
            raise RuntimeError("PhysicsWorld.step needs a started, paused world")
        return [self._tick() for _ in range(count)]

    def set_box_state(self, position: Sequence[float] = BOX_START,
                      orientation: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
                      linear_velocity: Sequence[float] = (0.0, 0.0, 0.0),
                      angular_velocity: Sequence[float] = (0.0, 0.0, 0.0)) -> int:
        """Put the box in this state before the next step (:meth:`BoxWorld.set_state`: metres, ``(x, y, z,
        w)``, m/s, rad/s, world frame; default: the SDF's start, at rest).

        Wrench messages queued, and those arriving until that next step is published, were computed from the
        old state: they are dropped (recorded with ``dropped``), that step takes no input and does not wait
        for one, and lockstep goes on with the answers to its publication. So what follows depends on the new
        state alone, to the last bit.

        Returns:
            the number of that next step, the first from this state: a check judges
            ``[s for s in trajectory if s.step >= it]``.
        """
        with self.lock:
            self.physics.set_state(position, orientation, linear_velocity, angular_velocity)
            for wrench in self._queued:
                wrench.dropped = True
            # lockstep: the answer to the last publication may still be on its way; the next step waits for it
            self._stale_answer = self.wait_for_input is not None and self._published > 0 and not self._fresh
            self._queued, self._restarted = [], True
            return self.physics.steps + 1

    def box_state(self) -> BoxState:
        """The box now (:class:`BoxState`)."""
        with self.lock:
            return self.physics.state()

    @property
    def trajectory(self) -> list[StepRecord]:
        """A copy of every :class:`StepRecord` so far, oldest first."""
        with self.lock:
            return list(self.physics.trajectory)

    def peers(self) -> tuple[int, int, int]:
        """``(subscribers of /tf, subscribers of /clock, publishers of the wrench topic)`` in the graph, the
        world's own excluded (0s before :meth:`start`): who is there to follow and push the box."""
        if self._node is None:
            return (0, 0, 0)
        return (self._tf_pub.get_subscription_count(), self._clock_pub.get_subscription_count(),
                self._node.count_publishers(self.wrench_topic))

    @property
    def sim_time(self) -> float:
        """Sim seconds of the last step."""
        return self.physics.time

    def wait_for_wrench(self, timeout: float) -> bool:
        """Wait (at most ``timeout`` wall seconds) until a wrench message has arrived; True when one has.

        A grader running a controller in lockstep waits for it, then sets the box's state
        (:meth:`set_box_state`) and judges from there: the steps before, which timed out while the controller
        started, then never count, and two runs give the same trajectory to the last bit.
        """
        with self.lock:
            return self.lock.wait_for(lambda: bool(self.wrenches) or self._closing, timeout) and bool(self.wrenches)

    def wait_for_sim_time(self, seconds: float, timeout: float) -> bool:
        """Wait (at most ``timeout`` wall seconds) until the sim time reaches ``seconds``; True when it has."""
        with self.lock:
            return self.lock.wait_for(lambda: self.physics.time >= seconds - 1e-9 or self._closing, timeout) \
                and not self._closing

    # --- stepping thread ---

    def _run(self) -> None:
        """The stepping loop: wait while paused, tick, keep the pace (SimulationRunner::Run's schedule)."""
        next_at = time.monotonic()
        while True:
            with self.lock:
                self.lock.wait_for(lambda: self._closing or not self._paused)
                if self._closing:
                    return
            self._tick()
            next_at = self._pace(next_at)

    def _pace(self, next_at: float) -> float:
        """Sleep until the next step is due; the time it was due (a late step moves the schedule on)."""
        if not self.real_time_factor:
            return time.monotonic()
        period = STEP_SIZE / self.real_time_factor
        next_at += period
        now = time.monotonic()
        if next_at < now:
            next_at = now + period
        with self.lock:
            self.lock.wait_for(lambda: self._closing or self._paused, max(0.0, next_at - now))
        return next_at

    def _tick(self) -> StepRecord:
        """Lockstep wait (if any), one step with the queued wrenches, then publish /tf and /clock."""
        timed_out = self._await_input()
        if self._restarted:
            timed_out = self._await_stale()
        with self.lock:
            taken, self._queued = ([], []) if self._restarted else (self._queued, [])
            applied = [w for w in taken if w.applied]
            force = tuple(sum(w.force[i] for w in applied) for i in range(3))
            torque = tuple(sum(w.torque[i] for w in applied) for i in range(3))
            entry = self.physics.step(force, torque, len(taken), timed_out)
            for wrench in taken:
                wrench.step = entry.step
            state, stamp = self.physics.state(), self.physics.time_ns
            self._fresh = self._restarted = False
            self._published += 1
            self.lock.notify_all()  # wait_for_sim_time
        self._publish(state, stamp)
        return entry

    def _await_input(self) -> bool:
        """Lockstep: wait for a wrench received after the last publication; True when the wait timed out (a
        :meth:`set_box_state` meanwhile ends the wait: that step takes no input)."""
        if self.wait_for_input is None or self._published == 0:
            return False
        with self.lock:
            return not self.lock.wait_for(lambda: self._fresh or self._restarted or self._closing,
                                          self.wait_for_input)

    def _await_stale(self) -> bool:
        """After :meth:`set_box_state` in lockstep: wait for (and so drop) the answer to the publication before
        it, lest it pass for the answer to the next one. False: that step never counts as timed out."""
        with self.lock:
            self.lock.wait_for(lambda: not self._stale_answer or self._closing, self.wait_for_input)
            self._stale_answer = False
        return False

    def _publish(self, state: BoxState, stamp_ns: int) -> None:
        """The box's pose on /tf (parent ``world``, child ``box``; not while :attr:`withhold_tf`), then the time on
        /clock, both at ``stamp_ns``."""
        from builtin_interfaces.msg import Time  # noqa: PLC0415 - ROS only when a world is served
        from geometry_msgs.msg import TransformStamped  # noqa: PLC0415 - ROS only when a world is served

        stamp = Time(sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000)
        transform = TransformStamped()
        transform.header.stamp, transform.header.frame_id, transform.child_frame_id = stamp, self.world, BOX
        t, r = transform.transform.translation, transform.transform.rotation
        t.x, t.y, t.z = state.position
        r.x, r.y, r.z, r.w = state.orientation
        try:
            if not self.withhold_tf:
                self._tf_pub.publish(self.types.tf_message(transforms=[transform]))
            self._clock_pub.publish(self.types.clock(clock=stamp))
        except Exception:  # noqa: BLE001 - the context was shut down under a step: close() follows
            if self.graph.context.ok():
                raise

    # --- callbacks (executor threads) ---

    def _on_wrench(self, msg: Any) -> None:
        record(self.graph, self.wrench_topic, msg)
        entity = (int(msg.entity.id), str(msg.entity.name), int(msg.entity.type))
        f, m = msg.wrench.force, msg.wrench.torque
        wrench = WrenchRecord(time.time(), self.physics.time, entity, wrench_link(*entity), (f.x, f.y, f.z),
                              (m.x, m.y, m.z))
        with self.lock:
            self.wrenches.append(wrench)
            if self._restarted:
                wrench.dropped, self._stale_answer = True, False
                self.lock.notify_all()
                return
            self._queued.append(wrench)
            self._fresh = True
            self.lock.notify_all()

    def _on_set_pose(self, request: Any, response: Any) -> Any:
        record(self.graph, f"{self.set_pose_service}/request", request)
        with self.lock:
            entry = self._set_pose(request)
            self.set_pose_requests.append(entry)
            if self.answer_delay > 0:
                self.lock.wait_for(lambda: self._closing, self.answer_delay)
            entry.answered_at = time.monotonic()
        response.success = entry.success
        record(self.graph, f"{self.set_pose_service}/response", response)
        return response

    def _set_pose(self, request: Any) -> SetPoseRecord:
        """Apply one set_pose request (holding :attr:`lock`); its record."""
        entity = (int(request.entity.id), str(request.entity.name), int(request.entity.type))
        p, q = request.pose.position, request.pose.orientation
        position, orientation = (p.x, p.y, p.z), (q.x, q.y, q.z, q.w)
        target = pose_target(entity[0], entity[1])
        applied = target == BOX_ID and all(map(math.isfinite, position))
        if applied:
            now = self.physics.state()
            velocities = (now.linear_velocity, now.angular_velocity) if self.keep_velocity_on_set_pose else ()
            try:
                self.physics.set_state(position, orientation, *velocities)
            except ValueError:  # a zero or non-finite quaternion: Physics refuses it
                applied = False
        success = target is not None if self.strict_set_pose else True
        return SetPoseRecord(time.time(), self.physics.time, entity, target, position, orientation, applied, success)
