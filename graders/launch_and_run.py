"""Grader for ``launch-and-run`` (tutorial ch. 10 and 23; contract in shared/LESSONS.md).

The learner's ``cli/run_and_launch.sh`` starts ``print_forever_node`` with
``ros2 run`` and the launch-files lesson's launch file with ``ros2 launch``, both
in the background, and waits. It runs in the check's graph (as kit.scripts runs scripts, with SIGINT
at its default action as in a terminal) while a
:class:`~graders._node_watch.NodeWatch` lists the nodes that join; :data:`RUN_SECONDS`
after both nodes are in the graph (or :data:`START_TIMEOUT` after the script
started, if they never both come) the grader presses Ctrl+C (SIGINT to the
script's process group, as a terminal does) and expects the script to end by
itself, exit code 0 and no traceback, once its nodes have stopped. Counting
from the nodes, not from the script's start: on a loaded machine a Ctrl+C at a
fixed 7 s landed in a node still importing rclpy, whose KeyboardInterrupt no
``try`` in ``main`` can catch, and the reference lost sigint_exit (CI, stop 42).
"""

from __future__ import annotations

from ros2course.kit import Check, Session, scripts
from ros2course.kit import topics_services as ts
from ._node_watch import NodeWatch, node_appeared
from ros2course.kit.nodes import sigint_exit
from ros2course.kit.quotes import LAUNCH_FILE, LAUNCH_NODE, LAUNCH_TOPIC
from ros2course.kit.quotes import PACKAGE as LAUNCH_PACKAGE

SCRIPT = "cli/run_and_launch.sh"
RUN_PACKAGE = "python_package_with_a_node"
RUN_NODE = "print_forever"  # shared/LESSONS.md, print-forever-node
RUN_COMMAND = f"ros2 run {RUN_PACKAGE} print_forever_node &"
LAUNCH_COMMAND = f"ros2 launch {LAUNCH_PACKAGE} {LAUNCH_FILE} &"
#: Seconds the script runs after both its nodes joined the graph, before Ctrl+C.
RUN_SECONDS = 2.0
#: Seconds the nodes may take to join: `ros2 launch` and two Python nodes start in 2-4 s on a busy
#: machine and took over 7 s while CI graded two lessons at once on 2 cores.
START_TIMEOUT = 20.0
#: Seconds it may take to end after Ctrl+C (launch's own escalation starts at 5 s; ROS_ENV.md).
EXIT_SECONDS = 5.0

SCRIPTED = ("script",)
CHECKS = [
    Check("build", "The packages build with colcon", 1),
    Check("script", f"{SCRIPT} exists and is valid bash", 1),
    Check("run_node", f"`ros2 run` starts the node /{RUN_NODE}", 2, RUN_COMMAND, needs=SCRIPTED),
    Check("launch_node", f"`ros2 launch` starts the node /{LAUNCH_NODE}, as the launch file configures it", 2,
          f"{LAUNCH_COMMAND} (on its own line, after the `ros2 run ... &` line): the launch file, not "
          "`ros2 run` of its executable under the launched node's name", needs=SCRIPTED),
    Check("keeps_running", "The script keeps running until Ctrl+C (it waits for its nodes)", 1,
          "end the script with `wait`: without it, bash reaches the end at once and the nodes lose their terminal",
          needs=SCRIPTED),
    Check("sigint_exit", "Ctrl+C ends the script with exit code 0 and no traceback, after its nodes stopped", 2,
          "`trap '...' INT` before the commands keeps bash alive when Ctrl+C comes; then a second `wait` waits "
          "for the nodes to finish", needs=("keeps_running",)),
]


def grade(s: Session) -> None:
    path = scripts.script(s, "script", SCRIPT)
    watch = NodeWatch(s)
    nodes = (f"/{RUN_NODE}", f"/{LAUNCH_NODE}")
    launched: list[str] = []  # what the launched node publishes, once its node is seen

    def both_started() -> bool:
        if all(node in watch.seen() for node in nodes):
            launched[:] = sorted(ts.endpoints(s.ros, LAUNCH_NODE, "publishers"))
            return f"/{LAUNCH_TOPIC}" in launched
        return False

    run = scripts.run_script(s, path, interrupt_after_s=RUN_SECONDS, exit_timeout=EXIT_SECONDS,
                             wait_for=both_started, first_timeout=START_TIMEOUT)
    watch.stop()
    # a node that only joined after Ctrl+C (a script that reached `ros2 launch` only then) does not count
    ctrl_c = run.interrupted_at if run.interrupted_at is not None else START_TIMEOUT
    node_appeared(s, "run_node", watch, nodes[0], RUN_COMMAND, before=ctrl_c)
    if watch.seen().get(nodes[1], ctrl_c + 1) <= ctrl_c and f"/{LAUNCH_TOPIC}" not in launched:
        # the launch file gives the node its topic_name (the launch-files lesson); its executable run alone
        # under that name (`ros2 run ... --ros-args -r __node:=...`) publishes the parameters lesson's default
        s.record("launch_node", False, f"{nodes[1]} appeared, but it publishes "
                 f"{', '.join(launched) or 'nothing'}, not /{LAUNCH_TOPIC}: not as the launch file "
                 f"{LAUNCH_FILE} starts it (its topic_name)", f"node {nodes[1]} publishing /{LAUNCH_TOPIC}, as "
                 f"`{LAUNCH_COMMAND}` starts it")
    else:
        node_appeared(s, "launch_node", watch, nodes[1], LAUNCH_COMMAND, before=ctrl_c)
    expected = f"still running {RUN_SECONDS:.0f} s after its nodes joined the graph (Ctrl+C ends it)"
    if run.interrupted:
        s.record("keeps_running", True, f"it was still running when Ctrl+C came, {ctrl_c:.1f} s after it "
                 "started", expected)
    else:
        s.record("keeps_running", False, f"it ended by itself ({run.describe()}) before Ctrl+C; its last output: "
                 f"{scripts.excerpt(run.stderr or run.stdout, 200)}", expected)
    if sigint_exit(s, "sigint_exit", run, EXIT_SECONDS):
        return
    if run.returncode is not None and run.returncode < 0:
        s.amend("sigint_exit", hint="bash itself was ended by Ctrl+C while its nodes were still stopping: "
                "`trap 'echo stopping' INT` keeps it alive, and a second `wait` waits for them")
    elif run.left_running:
        s.amend("sigint_exit", hint="Ctrl+C ends the first `wait` at once, while the nodes are still stopping: "
                "a second `wait` after it waits until they have finished")
