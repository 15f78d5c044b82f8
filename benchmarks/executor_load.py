"""What the grading session's executor costs on a topic of a given rate (issue 38's question).

The session's node spins in an rclpy ``MultiThreadedExecutor(num_threads=2)`` (``ros2course.run.probes.RosSession``):
the stand-in action servers of the action lessons need a goal's long execute callback and a cancel answered at once.
While a callback of the node's default (mutually exclusive) callback group runs in the pool, rclpy's
``MultiThreadedExecutor`` finds the group's next ready entity again at once and loops without waiting, so a fast
topic keeps a core busy and starves the callback that stores the messages. This measures it: a publisher in another
process (its own rclpy, a timer of ``1 / RATE`` s) and a :class:`~ros2course.run.probes.TopicProbe` in the session;
for each executor, the messages the probe stored in 6 s and the CPU seconds the grader's process spent meanwhile::

    python benchmarks/executor_load.py                  # 500, 100, 20 and 2 Hz
    python benchmarks/executor_load.py --rates 100

Each rate and executor runs in a child process of its own (one rclpy context each). Measured on the 2-core machine
of 2026-11-28 (stop 61): 500 Hz: multi-threaded 94-104 % of a core, 176-725 of ~3000 messages kept; single-threaded
17 %, all kept. 200 Hz: 651 of 1200 and 83 % against 1198 and 9 %. 100 Hz: 60 % and 498 of 600 against 7 % and 600. 20 Hz: 5 % against 2 %, all kept in both.
2 Hz: 1 % against 0 %. The lessons probe topics at 20 Hz at most through the session; the 500 Hz joint stream and
the 100 Hz targets of sas-robot-driver have probes with a single-threaded executor of their own
(``graders/_joint_stream.py``).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

PUBLISHER = """
import os, rclpy
from std_msgs.msg import String
rclpy.init(); node = rclpy.create_node('fast'); pub = node.create_publisher(String, '/fast', 10)
msg = String(data='x')
node.create_timer(float(os.environ['PERIOD']), lambda: pub.publish(msg))
rclpy.spin(node)
"""

WARM_UP = 3.0  # seconds before the window: discovery and the first messages
WINDOW = 6.0  # seconds measured


def measure(executor: str, rate: float) -> dict[str, float]:
    """In this process: a session with ``executor`` (``"multi"``, as graded, or ``"single"``) hears a ``rate`` Hz
    publisher for :data:`WINDOW` s; ``{"messages", "sent", "cpu_seconds", "core_share"}``."""
    from ros2course.ros import env as env_mod  # noqa: PLC0415 - in the child only

    env_mod.activate_process()
    if executor == "single":
        import rclpy.executors as executors  # noqa: PLC0415 - in the child only

        executors.MultiThreadedExecutor = lambda num_threads=2, context=None: executors.SingleThreadedExecutor(
            context=context)
    from std_msgs.msg import String  # noqa: PLC0415 - in the child only

    from ros2course.run.probes import RosSession, TopicProbe  # noqa: PLC0415 - in the child only

    with RosSession() as ros:
        env = {**ros.learner_env(dict(os.environ)), "PERIOD": str(1.0 / rate)}
        publisher = subprocess.Popen([sys.executable, "-c", PUBLISHER], env=env)
        try:
            probe = TopicProbe(ros, "/fast", String)
            time.sleep(WARM_UP)
            before, count, begin = resource.getrusage(resource.RUSAGE_SELF), len(probe.samples()), time.monotonic()
            time.sleep(WINDOW)
            after, end = resource.getrusage(resource.RUSAGE_SELF), time.monotonic()
            kept = len(probe.samples()) - count
        finally:
            publisher.terminate()
            publisher.wait(timeout=10)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"messages": kept, "sent": round(rate * (end - begin)), "cpu_seconds": round(cpu, 2),
            "core_share": round(cpu / (end - begin), 3)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rates", type=float, nargs="+", default=[500.0, 100.0, 20.0, 2.0], help="Hz")
    parser.add_argument("--child", nargs=2, metavar=("EXECUTOR", "RATE"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(measure(args.child[0], float(args.child[1]))))
        return
    print("| rate | executor | messages kept / sent | grader CPU (share of a core) |")
    print("|---|---|---|---|")
    for rate in args.rates:
        for executor in ("multi", "single"):
            out = subprocess.run([sys.executable, __file__, "--child", executor, str(rate)], capture_output=True,
                                 text=True, timeout=120, check=True).stdout.strip().splitlines()[-1]
            row = json.loads(out)
            print(f"| {rate:g} Hz | {executor}-threaded | {row['messages']} / {row['sent']} | "
                  f"{row['cpu_seconds']:.2f} s ({100 * row['core_share']:.0f} %) |")


if __name__ == "__main__":
    main()
