"""The grader's physics world: a simulated Gazebo world behind the author's interfaces (issue 40).

Gazebo does not install on a pip-only machine; :mod:`ros2course.run.physics` runs the author's
``shapes_with_tf2_and_wrench`` box on MuJoCo and serves what Gazebo and ``ros_gz_bridge`` serve the
learner's nodes (``set_pose``, the wrench topic, the box on ``/tf``, ``/clock``). This is the kit's door to
it: a world in the part's graph, closed with the part, plus the names a grader judges with.
"""

from __future__ import annotations

from typing import Any

from ros2course.kit.session_protocol import Session
from ros2course.run.physics import (
    BOX,
    BOX_ID,
    BOX_LINK_ID,
    FRICTION,
    GRAVITY,
    STEP_SIZE,
    WORLD,
    BoxState,
    BoxWorld,
    PhysicsWorld,
    StepRecord,
    load_types,
)

__all__ = ["BOX", "BOX_ID", "BOX_LINK_ID", "FRICTION", "GRAVITY", "STEP_SIZE", "WORLD", "BoxState", "BoxWorld", "PhysicsWorld",
           "StepRecord", "physics_world"]


def physics_world(s: Session, *, paused: bool = False, graph: Any = None, **options: Any) -> PhysicsWorld:
    """A :class:`~ros2course.run.physics.PhysicsWorld` serving in ``graph`` (default ``s.graph``), started
    (stepping unless ``paused``), closed when the part ends. Closers run newest first: a world created
    before the learner's node is still there while the node's Ctrl+C is judged; one created after it (a node
    that must first run with no world to find, and say that it waits, as in gazebo-custom-nodes) is closed
    first, and the Ctrl+C is judged with no world, which a node that waits for one must survive anyway.

    Args:
        options: :class:`~ros2course.run.physics.PhysicsWorld`'s keywords (``world``, ``friction``,
            ``real_time_factor`` in sim seconds per wall second, ``wait_for_input`` in wall seconds for
            lockstep, ``strict_set_pose``, ``withhold_tf``: /clock without /tf while true).

    Raises:
        MissingRequirement: MuJoCo is not installed (hint: ``pip install 'ros2course[gazebo]'``).
        NotGradable: the Gazebo interfaces (ros_gz_interfaces, the nav2 component) do not load.
    """
    world = PhysicsWorld(graph or s.graph, load_types(s.base_env), **options)
    s.on_close(world.close)
    return world.start(paused=paused)
