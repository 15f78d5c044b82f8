"""Grader for ``lifecycle-node`` (a managed node; contract in chapters/lifecycle-node/CONTRACT.md).

Black-box, as ``ros2 lifecycle`` would drive it: the grader calls the node's
``/<node>/change_state`` and ``/<node>/get_state`` services (lifecycle_msgs)
with its own client and judges, state by state, what the node sends on
``/heartbeat``. The sequence is the managed-node state machine of
design.ros2.org/articles/node_lifecycle.html::

    unconfigured -configure-> inactive -activate-> active -deactivate-> inactive
    -cleanup-> unconfigured -configure-> inactive -activate-> active -shutdown-> finalized, then Ctrl+C

and two more runs, each in a graph of its own: shutdown straight from unconfigured, and configure then
shutdown from inactive (the state machine's other two shutdowns).

"Nothing while X" is judged on the messages' send stamps (written while the
node was in X, whenever they arrive), rates on send stamps too; a quiet
window ends early on the first message sent in it. The grader's ``ros2 lifecycle``
and the procedure of each check are in the lesson's helper, graders/_lifecycle.py.
"""

from __future__ import annotations

import re

from ros2course import kit
from ros2course.kit import Check, Session, Unmet, checks
from ros2course.kit import topics_services as ts

from . import _lifecycle

PACKAGE = "python_package_with_a_lifecycle_node"
EXECUTABLE = "lifecycle_heartbeat_node"
NODE = "lifecycle_heartbeat"
TOPIC = "/heartbeat"
TOPIC_TYPE = "std_msgs/msg/String"
PERIOD = 0.2  # seconds between heartbeats while active (5 Hz; CONTRACT.md)
SAMPLES = 6  # messages per active window -> 5 intervals (shared/LESSONS.md minimum)
#: Seconds each inactive state is watched for a message: 3 periods, so a node that ignores its
#: state sends about 3 (a quiet window ends at the first one sent in it; a correct node costs
#: the whole window, four times per check).
QUIET = 3 * PERIOD
#: What each message says (the lesson: 'Heartbeat 0', 'Heartbeat 1', ...); the first number seen is not judged:
#: the timer runs (and counts) while the node is inactive, its messages dropped by the lifecycle publisher.
HEARTBEAT = re.compile(r"Heartbeat (-?\d+)")

#: Seconds of observation the contract needs: four quiet windows and two active ones.
WINDOW = 4 * QUIET + 2 * SAMPLES * PERIOD

RUN = ("executable",)
CHECKS = [
    Check("build", "The package builds with colcon", 1),
    *checks.started("", PACKAGE, EXECUTABLE, NODE),
    Check("managed", f"It is a managed node: /{NODE}/get_state answers 'unconfigured' at start", 2,
          "subclass rclpy.lifecycle.LifecycleNode (from rclpy.lifecycle import LifecycleNode), not rclpy.node.Node: "
          "only a LifecycleNode offers the change_state/get_state services ros2 lifecycle uses", needs=RUN),
    Check("quiet_unconfigured", f"Nothing is published on {TOPIC} while unconfigured", 1,
          "create nothing in __init__: the publisher and the timer belong in on_configure", needs=("managed",)),
    Check("configure", "configure succeeds: unconfigured -> inactive", 2,
          "on_configure creates the lifecycle publisher and the timer and returns TransitionCallbackReturn.SUCCESS",
          needs=("managed",)),
    Check("quiet_inactive", f"Nothing is published on {TOPIC} while inactive", 2,
          "create the publisher with self.create_lifecycle_publisher(String, 'heartbeat', 10): its publish() drops "
          "messages until the node is activated (a plain create_publisher() publishes in every state)",
          needs=("configure",)),
    Check("activate", "activate succeeds: inactive -> active", 1,
          "on_activate returns super().on_activate(state) (TransitionCallbackReturn.SUCCESS)", needs=("configure",)),
    Check("active_messages", f"While active it publishes {TOPIC_TYPE} 'Heartbeat N' on {TOPIC}, N counting up", 2,
          "return super().on_activate(state) from on_activate: the base class is what enables the lifecycle "
          "publisher", needs=("activate",)),
    Check("active_rate", f"While active it publishes every {PERIOD} s ({1 / PERIOD:.0f} Hz)", 2,
          f"create the timer in on_configure with self.create_timer({PERIOD}, self.timer_callback)",
          needs=("active_messages",)),
    Check("deactivate", "deactivate succeeds: active -> inactive", 1,
          "on_deactivate must return a TransitionCallbackReturn: return super().on_deactivate(state)",
          needs=("activate",)),
    Check("quiet_deactivated", f"Nothing is published on {TOPIC} after deactivate", 2,
          "return super().on_deactivate(state) from on_deactivate: the base class disables the lifecycle publisher",
          needs=("deactivate",)),
    Check("reactivate", f"After deactivate, activate works again: one heartbeat every {PERIOD} s", 1,
          "create the timer once, in on_configure, and let the lifecycle publisher decide what goes out: a timer "
          "cancelled in on_deactivate never fires again, one created in on_activate doubles on a second activate",
          needs=("quiet_deactivated",)),
    Check("cleanup", f"cleanup succeeds (inactive -> unconfigured) and the node's {TOPIC} publisher is gone", 2,
          "in on_cleanup destroy what on_configure created: self.destroy_timer(self.timer) and "
          "self.destroy_lifecycle_publisher(self.heartbeat_publisher)", needs=("deactivate",)),
    Check("reconfigure", f"After cleanup, configure and activate work again: one heartbeat every {PERIOD} s", 2,
          "on_cleanup must leave the node as __init__ did: a timer that survives cleanup keeps firing beside the "
          "one the next on_configure creates", needs=("cleanup",)),
    Check("shutdown", f"shutdown from active reaches finalized, and nothing is published on {TOPIC} after it", 2,
          "in on_shutdown destroy the timer and the publisher (shutdown may come while active: the base class does "
          "not deactivate the publisher) and return TransitionCallbackReturn.SUCCESS", needs=("managed",)),
    Check("shutdown_destroys", f"shutdown destroys the node's {TOPIC} publisher (it leaves the graph)", 1,
          "in on_shutdown: if self.heartbeat_publisher is not None: self.destroy_lifecycle_publisher(...), as "
          "on_cleanup does", needs=("shutdown",)),
    checks.ctrl_c("sigint_exit", "the finalized node", 1, needs=RUN),
    Check("shutdown_any_state", "shutdown also reaches finalized from unconfigured (before any configure) and from "
          "inactive, destroying what exists", 2, "__init__ sets self.heartbeat_publisher = None and self.timer = None, and on_shutdown "
          "destroys each only if it is not None: shutdown may come before configure ever ran", needs=("managed",)),
]


def grade(s: Session) -> None:
    """Start the node, drive it through every transition and watch /heartbeat in each state, then Ctrl+C."""
    # a wheel of the venv; imported here because graders load for CHECKS without ROS
    from std_msgs.msg import String  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    path = kit.executable(s, "executable", PACKAGE, EXECUTABLE)
    # the probe before the node starts: nothing it sends is missed
    stream = _lifecycle.Stream(ts.listen(s, TOPIC, String), TOPIC, TOPIC_TYPE, period=PERIOD, samples=SAMPLES,
                               quiet=QUIET, pattern=HEARTBEAT)
    # a misnamed node is still driven through its own services (need_node=False)
    node = kit.start_node(s, "node_name", path, NODE, sigint_check="sigint_exit", need_node=False)
    if node.name is None:
        raise Unmet(s.results["node_name"].observed)
    life = _lifecycle.Lifecycle(s, node)
    since = _lifecycle.managed(s, life)
    try:
        _lifecycle.quiet(s, "quiet_unconfigured", stream, node, since, "unconfigured")
        since = _lifecycle.transition(s, "configure", life, _lifecycle.CONFIGURE, _lifecycle.INACTIVE)
        _lifecycle.quiet(s, "quiet_inactive", stream, node, since, "inactive (after configure)", after_match=True)
        since = _lifecycle.transition(s, "activate", life, _lifecycle.ACTIVATE, _lifecycle.ACTIVE)
        _lifecycle.active(s, stream, node, since)
        since = _lifecycle.transition(s, "deactivate", life, _lifecycle.DEACTIVATE, _lifecycle.INACTIVE)
        _lifecycle.quiet(s, "quiet_deactivated", stream, node, since, "inactive (after deactivate)")
        _lifecycle.reactivate(s, life, stream)
        _lifecycle.cleanup(s, life, TOPIC)
        _lifecycle.reconfigure(s, life, stream)
        _lifecycle.shutdown(s, life, stream)
    finally:  # judged whatever stopped the sequence above: the runs are of their own
        _lifecycle.shutdown_any_state(s, path, EXECUTABLE, node.name, TOPIC)
