"""Kit steps for lessons whose answer is a bash script of ``ros2`` commands (tutorial ch. 10, 16, 19, 21, 23, 24).

The grader starts its own "mystery" nodes in the check's private graph, then
runs the learner's script there: ``bash <script>`` with the sourced workspace,
the check's ``ROS_DOMAIN_ID`` and localhost discovery (``learner_env`` of the part's graph),
in its own process group with a deadline and capped output
(:meth:`Session.start_program`). When the script's process is stopped,
every process carrying its run marker is killed too, so a ``ros2`` daemon that
the script's first ``ros2 topic list`` spawned (ros2cli's ``spawn_daemon``
detaches it with ``setsid``) does not outlive the check. A grader whose script
lists the graph starts a daemon first (``run_script(daemon_sees=...)``,
:func:`ros2_daemon`); its own probes are rclpy nodes. The discovery steps a
lesson teaches (``--spin-time``, ``ros2 daemon start`` and asking again) are
graded by a second run where what the script must find appears only after it
has started looking (:func:`run_script_first`).

Typical use::

    path = kit.scripts.script(s, "script", "cli/inspect_topics.sh")
    run = kit.scripts.run_script(s, path, timeout=40.0)
    kit.scripts.ended(s, "ends", run, "every command in it ends by itself (`--once`)")
    kit.scripts.printed(s, "echo", run, [quote_text], "a message from /amazing_quote_8341",
                        "ros2 topic echo --once /amazing_quote_8341")
"""

from __future__ import annotations

import dataclasses
import re
import shutil
import subprocess
import time
import xmlrpc.client
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ros2course.grade.checklist import Unmet
from ros2course.kit.session_protocol import Session
from ros2course.kit.programs import ProgramRun, interrupt_after, run_program
from ros2course.run.probes import wait_until

#: Characters of a script's output quoted back in feedback.
EXCERPT = 400


def script(s: Session, check_id: str, relative: str) -> Path:
    """Record ``check_id``: the learner's script exists in the workspace and is valid bash (``bash -n``).

    Args:
        relative: path from the workspace root, e.g. ``"cli/inspect_topics.sh"``.

    Returns:
        The script's absolute path.

    Raises:
        Unmet: the file is missing or bash rejects its syntax (the message quotes bash's own error).
    """
    path = s.workspace_root / relative
    expected = f"{relative} exists and bash accepts its syntax"
    if not path.is_file():
        s.record(check_id, False, f"no file {relative}", expected,
                 hint=f"create {relative} in your workspace (the starter has one with TODOs)")
        raise Unmet(f"{relative} is missing")
    syntax = subprocess.run(["bash", "-n", str(path)], capture_output=True, text=True, timeout=10, check=False)
    if syntax.returncode != 0:
        first = (syntax.stderr.strip().splitlines() or ["syntax error"])[0].replace(str(path), relative)
        s.record(check_id, False, f"bash rejects it: {first}", expected, hint="run `bash -n " + relative + "` and fix the line it names")
        raise Unmet(f"{relative} is not valid bash")
    s.record(check_id, True, f"{relative} ({len(path.read_text(errors='replace').splitlines())} lines)", expected)
    return path


def run_script(s: Session, path: Path, *, timeout: float = 60.0, graph=None,
               interrupt_after_s: float | None = None, exit_timeout: float = 5.0,
               args: Iterable[str] = (), daemon_sees: Iterable[str] = (),
               wait_for: Callable[[], bool] | None = None, first_timeout: float = 10.0) -> ProgramRun:
    """Run ``bash path`` in the check's ROS graph and return what it did; it is stopped at ``timeout`` seconds.

    Args:
        path: from :func:`script`.
        timeout: seconds the script may run before it is stopped (``timed_out``: a command in it never ended).
        graph: the :class:`~ros2course.run.probes.RosSession` whose domain it joins (default ``s.graph``: the part's own graph, else ``s.ros``).
        interrupt_after_s: for scripts that run until stopped (``ros2 run``, ``ros2 launch``): press
            Ctrl+C (SIGINT to its process group) after this many seconds, then wait ``exit_timeout``.
        wait_for: with ``interrupt_after_s``: the seconds count from the moment this predicate first
            holds (e.g. every node the script starts is in the graph), waited for at most
            ``first_timeout`` s (:func:`~ros2course.kit.programs.interrupt_after`).
        args: extra arguments after the script path.
        daemon_sees: names (nodes as ``/name``, topics, services) the grader started: when given, a
            ``ros2`` daemon is started in the check's domain first and the script runs once that daemon
            lists them all (:func:`ros2_daemon`), as in a learner's terminal where a daemon has been
            running for a while. Without it, the script's first ``ros2 ... list`` would spawn one and
            listen for the graph itself for only ``--spin-time`` seconds: on a machine running two checks
            at once it printed nothing in 7 of 16 runs (issue 24).

    The working directory is the workspace root; nothing of the learner's runs
    after this returns (processes with the run's marker are killed, ``ros2``
    daemons included).
    """
    env = (graph or s.graph).learner_env(s.overlay())
    argv = ["bash", str(path), *args]
    label = path.stem
    if "ROS_HOME" not in env:  # the ros2 CLI's daemon and logs write there, as the submission
        env["ROS_HOME"] = str(s.submission_folder(f"{label}.ros_home"))
    wanted = list(daemon_sees)
    if wanted:
        ros2_daemon(s, env, wanted, label)
    if interrupt_after_s is not None:
        # Ctrl+C as in a terminal: bash starts with SIGINT at its default action, whatever
        # ros2course's own disposition (LearnerProcess: a bash that starts with it ignored can
        # neither die of Ctrl+C nor trap it, bash(1) SIGNALS, so a script without `trap` would look right).
        return interrupt_after(s, argv, label, interrupt_after_s, exit_timeout=exit_timeout, env=env,
                               cwd=s.workspace_root, wait_for=wait_for, first_timeout=first_timeout)
    return run_program(s, argv, label, timeout=timeout, env=env, cwd=s.workspace_root)


#: The nodes ``ros2`` commands make: ``_ros2cli_<pid>``, the node a command listens with itself when no daemon
#: answers (ros2cli ``node/direct.py`` DirectNode, ``node/__init__.py`` NODE_NAME_PREFIX), and
#: ``_ros2cli_daemon_<domain>_<uuid>``, the daemon (ros2cli ``daemon/__init__.py``).
ROS2CLI_NODE = re.compile(r"_ros2cli_(\d+|daemon_\d+_[0-9a-f]+)")
#: Seconds to wait for the script's first ``ros2`` command to join the graph before starting the late part anyway.
FIRST_COMMAND_TIMEOUT = 10.0
#: Bounds (seconds) of :func:`late_by`.
LATE_BY_MIN = 3.0
LATE_BY_MAX = 10.0


def late_by(first_run: ProgramRun, low: float = LATE_BY_MIN, high: float = LATE_BY_MAX) -> float:
    """How late (seconds after the script's first ``ros2`` command) :func:`run_script_first`'s node should join:
    as long as ``first_run`` (the same script's run against a graph that had everything from the start) took,
    between ``low`` and ``high``.

    A script that looks once and gives up has given up within its whole first run's time, however slow the
    machine, so a node that joins later than that is missed by it and found by a script that asks again; a
    fixed delay let a busy machine's slow commands reach the node in time (CI: inspect-params' asks-at-once
    fixture got full marks with a fixed 3 s). ``high`` bounds what a correct script must wait (the tutorial's
    loop asks up to 10 times, a second apart).
    """
    return min(max(first_run.seconds, low), high)


@dataclasses.dataclass(frozen=True)
class LateRun:
    """A run of :func:`run_script_first`.

    Attributes:
        run: what the script did (stopped early once ``until`` held).
        first_command_at: seconds after the script started when its first ``ros2`` command joined the
            graph (None: none did within :data:`FIRST_COMMAND_TIMEOUT`).
        started_at: seconds after the script started when the grader's late part was started.
    """

    run: ProgramRun
    first_command_at: float | None
    started_at: float

    def describe(self) -> str:
        """When things happened, for an "observed" sentence."""
        first = ("its first ros2 command joined the graph after "
                 f"{self.first_command_at:.1f} s" if self.first_command_at is not None
                 else f"no ros2 command of it joined the graph within {FIRST_COMMAND_TIMEOUT:.0f} s")
        return f"{first}; the grader's node started {self.started_at:.1f} s after the script"


def run_script_first(s: Session, path: Path, start: Callable[[], Any], *, late_by: float,
                     timeout: float = 30.0, until: Callable[[str], bool] | None = None,
                     args: Iterable[str] = ()) -> LateRun:
    """Run ``bash path`` in a graph where what it must discover appears only after it has started looking.

    The situation the tutorial's discovery advice is for (ch. 19 and 21: a terminal where no
    ``ros2`` daemon runs yet, a node that has not been discovered when the first command asks):
    no daemon is started for the script, so its first ``ros2 ... list`` spawns one and meanwhile
    listens for the graph itself for ``--spin-time`` seconds (0.5 by default; ros2cli
    ``node/strategy.py``, ``node/direct.py``), and ``start()`` is called ``late_by`` seconds
    after the script's first ``ros2`` command joined the graph (its own node or the daemon it
    spawned: :data:`ROS2CLI_NODE`). A script that looks once and gives up (no ``--spin-time``,
    no asking again until the name shows up) misses it whatever the machine's load, and one that
    waits as the lesson teaches finds it: the times count from what the script did, not from the
    clock, so a slow interpreter start shifts both alike.

    Call it inside ``s.part(..., own_graph=True)`` so the graph is fresh: no daemon, none of the
    grader's earlier nodes; ``start`` then creates the grader's node in ``s.graph``.

    Args:
        start: starts what the script must find (e.g. a :class:`~ros2course.kit.mystery.MysteryNode`).
        late_by: seconds from the script's first ``ros2`` command to ``start()``.
        timeout: seconds the script may run in all.
        until: stop the script early once its standard output so far makes this True (what the
            check judges has been printed: the rest of the script would only cost time).
        args: extra arguments after the script path.
    """
    graph = s.graph
    graph.node  # noqa: B018 - the grader's participant joins first, so it sees the script's first command at once
    env = graph.learner_env(s.overlay())
    label = f"{path.stem}.late"
    if "ROS_HOME" not in env:
        env["ROS_HOME"] = str(s.submission_folder(f"{label}.ros_home"))

    def first_command() -> bool:
        return any(ROS2CLI_NODE.fullmatch(name) for name, _ in graph.node.get_node_names_and_namespaces())

    proc = s.start_program(["bash", str(path), *args], label, env=env, cwd=s.workspace_root,
                           deadline=timeout + FIRST_COMMAND_TIMEOUT + 10.0)
    begin = time.monotonic()
    with s.phase("run"):
        seen = wait_until(lambda: proc.poll() is not None or first_command(), FIRST_COMMAND_TIMEOUT, interval=0.02)
        first_at = time.monotonic() - begin if seen and proc.poll() is None else None
        wait_until(lambda: proc.poll() is not None, late_by if first_at is not None else 0.0, interval=0.02)
        started_at = time.monotonic() - begin
        start()
        left = max(0.0, timeout - (time.monotonic() - begin))
        finished = wait_until(lambda: proc.poll() is not None or (until is not None and until(proc.stdout())),
                              left, interval=0.05)
    seconds = time.monotonic() - begin
    report = proc.stop(sigint_timeout=0.5, sigterm_timeout=1.0)
    run = ProgramRun(report.returncode, proc.stdout(), proc.stderr(), not finished, seconds, report.traceback)
    return LateRun(run, first_at, started_at)


#: ros2cli's daemon serves XML-RPC on 127.0.0.1 at this port plus ROS_DOMAIN_ID (ros2cli.daemon.get_port).
DAEMON_BASE_PORT = 11511
#: Seconds to wait for the daemon to list the grader's names (Fast DDS discovery: well under 1 s when idle).
DAEMON_TIMEOUT = 15.0


class _QuickTransport(xmlrpc.client.Transport):
    """XML-RPC over HTTP with a 2 s socket timeout (a daemon that hangs must not hang the check)."""

    def make_connection(self, host):
        connection = super().make_connection(host)
        connection.timeout = 2.0
        return connection


def ros2_daemon(s: Session, env: dict[str, str], names: Iterable[str], label: str,
                timeout: float = DAEMON_TIMEOUT) -> bool:
    """Start a ``ros2`` daemon in ``env``'s ROS domain and wait until it lists every one of ``names``.

    The daemon runs as the learner's programs do (``ros2 daemon start`` through
    :meth:`Session.start_program`, so it carries that run's marker and is
    stopped with the check). The grader asks it over its XML-RPC interface
    (ros2cli ``daemon/__init__.py``: ``get_node_names_and_namespaces``,
    ``get_topic_names_and_types``, ``get_service_names_and_types``), the very
    answers ``ros2 node/topic/service list`` print from it.

    Args:
        env: the script's environment (``ROS_DOMAIN_ID`` set).
        names: node names as ``/name``, topic or service names.
        label: log file name prefix (``<label>.daemon``).
        timeout: seconds to wait, then the script runs anyway (its own commands then show what happens).

    Returns:
        True when the daemon listed every name in time.
    """
    ros2 = shutil.which("ros2", path=env.get("PATH"))
    domain = env.get("ROS_DOMAIN_ID", "")
    if ros2 is None or not domain.isdigit():
        return False
    s.start_program([ros2, "daemon", "start"], f"{label}.daemon", env=env, deadline=timeout + 60.0)
    proxy = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{DAEMON_BASE_PORT + int(domain)}/ros2cli/",
                                      transport=_QuickTransport(), allow_none=True)
    wanted = set(names)

    def listed() -> bool:
        try:
            seen = {name for name, _ in proxy.get_topic_names_and_types()}
            seen |= {name for name, _ in proxy.get_service_names_and_types()}
            seen |= {f"{ns.rstrip('/')}/{name}" for name, ns in proxy.get_node_names_and_namespaces()}
        except (OSError, xmlrpc.client.Error, ValueError, TypeError):
            return False
        return wanted <= seen

    with s.phase("start"):
        return wait_until(listed, timeout, interval=0.2)


def excerpt(text: str, limit: int = EXCERPT) -> str:
    """The last ``limit`` characters of ``text`` on one line, for an "observed" sentence ("" -> "nothing")."""
    flat = " | ".join(line.strip() for line in text.strip().splitlines() if line.strip())
    if not flat:
        return "nothing"
    return flat if len(flat) <= limit else "..." + flat[-limit:]


def ended(s: Session, check_id: str, run: ProgramRun, expected: str) -> bool:
    """Record ``check_id``: the script ended by itself, with exit code 0, before its deadline.

    A script still running at the deadline names the usual cause (a ``ros2 topic
    echo`` or ``pub`` without ``--once``); a non-zero exit quotes its last error line. A script that ended
    but left a command it started running (``ros2 topic hz /chatter &``, never stopped: it outlives the
    script in the learner's terminal) fails too, naming it (:attr:`ProgramRun.left_running`, ``ros2``
    daemons aside; a child killed as the script ends gets :data:`~ros2course.kit.programs.LEFT_GRACE`).
    """
    if run.timed_out:
        s.record(check_id, False, f"your script was {run.describe()}", expected,
                 hint="a command in it never ends: `ros2 topic echo` and `ros2 topic pub` need `--once`")
        return False
    if run.returncode != 0:
        last = excerpt(run.stderr or run.stdout, 200)
        s.record(check_id, False, f"your script ended with {run.describe()}; its last output: {last}", expected,
                 hint="run it yourself in a sourced terminal and fix the first command that fails")
        return False
    if run.left_running:
        s.record(check_id, False, f"your script ended ({run.describe()}), but left {len(run.left_running)} "
                 f"process(es) it started running: {run.left_running_text()}", expected,
                 hint="a command started with & outlives the script: run it in the foreground with an end "
                 "(--once, timeout N), or not at all")
        return False
    s.record(check_id, True, f"it ended by itself ({run.describe()})", expected)
    return True


def printed(s: Session, check_id: str, run: ProgramRun, needles: Iterable[str], what: str,
            command: str, whole_lines: bool = False, line_text: Callable[[str], str] = str.rstrip) -> bool:
    """Record ``check_id``: every one of ``needles`` appears in the script's standard output.

    Args:
        needles: texts that only the real command can print (the check's random values).
        what: what they are, for feedback ("the message on /amazing_quote_8341").
        command: the command that prints them, quoted in the hint ("ros2 topic echo --once /amazing_quote_8341").
        whole_lines: each needle must be a whole output line, unindented (``ros2 interface show``
            prints a nested message's fields indented under the field holding it: those are not
            the nested message's own definition).
        line_text: with ``whole_lines``, what of an output line is compared (default: the line
            without trailing blanks; ``ros2 param list --param-type`` appends `` (type: ...)``).
    """
    lines = {line_text(line) for line in run.stdout.splitlines()}
    missing = [needle for needle in needles if (needle not in lines if whole_lines else needle not in run.stdout)]
    expected = f"your script prints {what} (`{command}` prints it)"
    if missing:
        s.record(check_id, False, f"your script did not print {what}: missing {', '.join(map(repr, missing))}; "
                 f"it printed: {excerpt(run.stdout)}", expected, hint=f"`{command}` prints it")
        return False
    s.record(check_id, True, f"it printed {what}", expected)
    return True


def daemon_port(domain_id: int) -> int:
    """The TCP port of the ``ros2`` daemon of ``domain_id`` (ros2cli ``get_daemon_port``: 11511 + domain id)."""
    return 11511 + domain_id


__all__ = ["EXCERPT", "LateRun", "daemon_port", "ended", "excerpt", "printed", "run_script",
           "run_script_first", "script"]
