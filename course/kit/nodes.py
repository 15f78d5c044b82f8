"""Kit steps for a learner's executables: find one as ``ros2 run`` does, start it as a node, judge Ctrl+C.

Each step records its own check and returns a value the grader goes on
with; when the value does not exist (no executable, the process died) the
step raises :class:`ros2course.grade.checklist.Unmet` and the engine marks the checks
that need it "not checked".
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ros2course.grade.checklist import Unmet
from ros2course.kit.session_protocol import Session
from ros2course.kit.programs import ProgramRun, judge_interrupted_run
from ros2course.run.probes import wait_until
from ros2course.run.process import LearnerProcess, rclpy_shutdown_race


#: Seconds a fresh instance runs after its node appeared before its Ctrl+C (:func:`start_node`'s second
#: run): past its start-up, into the spin loop the first instance was stopped in.
SETTLE = 0.5


def executable(s: Session, check_id: str, package: str, name: str, hint: str = "") -> Path:
    """Record ``check_id`` on whether ``ros2 run package name`` finds the executable; return its path.

    The lookup is ros2run's: the package's prefix in the ament index of the
    sourced workspace, then ``<prefix>/lib/<package>/<name>``.

    Raises:
        Unmet: not found (nothing to run).
    """
    path, observed = s.find_executable(package, name)
    s.record(check_id, path is not None, observed,
             f"ros2 run {package} {name} finds install/{package}/lib/{package}/{name}", hint or None)
    if path is None:
        raise Unmet(f"there is no {name} executable to run")
    return path


def process_state(proc: LearnerProcess) -> str:
    """A sentence on whether ``proc`` is still running; if it ended, how (:meth:`LearnerProcess.exit_state`:
    the same account as the engine's ``process`` diagnosis), with its last traceback or ERROR/FATAL line."""
    ended = proc.exit_state()
    if ended is None:
        return "the process is still running"
    return f"the process {ended.describe()}" + (f" ({ended.last_line})" if ended.last_line else "")


@dataclasses.dataclass
class StartedNode:
    """A learner executable started by :func:`start_node`.

    Attributes:
        proc: the running process (stopped by the engine at the end of the check).
        name: the node to inspect: the contract's name when it appeared, else
            the only new node of the graph (a misnamed node is still graded
            on what it does), else None.
        found: whether the contract's node name appeared.
    """

    proc: LearnerProcess
    name: str | None
    found: bool

    def alive(self) -> bool:
        """True while the process runs."""
        return self.proc.poll() is None

    def ended(self) -> bool:
        """True once the process exited (an ``abort=`` for waits)."""
        return self.proc.poll() is not None


def start_node(s: Session, check_id: str, path: Path, node: str, *, sigint_check: str | None = None,
               args: Iterable[str] = (), label: str | None = None, graph: Any = None,
               timeout: float = 10.0, grace: float = 3.0, need_node: bool = True,
               aliases: Iterable[str] = ()) -> StartedNode:
    """Start ``path`` and record ``check_id`` on whether a node called ``node`` appears in the graph.

    Args:
        aliases: other names accepted for the node (see :func:`wait_for_node`).
        sigint_check: a check judged when the current part ends: Ctrl+C ends the
            process with exit code 0 and no traceback (:func:`sigint_exit`),
            even when a later step raised :class:`Unmet`.
        args: extra arguments (e.g. ``["--ros-args", "-p", "period:=0.25"]``).
        label: name of its log files (default: the executable's name).
        graph: the :class:`~ros2course.run.probes.RosSession` to run in (default ``s.graph``: the part's own graph, else ``s.ros``).
        timeout: seconds to wait for the node (a later process of a check can
            take ~3 s to be discovered: Fast DDS's announcement period).
        grace: stop waiting this many seconds after other nodes appeared without it.
        need_node: raise :class:`Unmet` when no node to inspect appeared at all.

    Raises:
        Unmet: the process died, or (``need_node``) no node to inspect appeared.
    """
    graph = graph or s.graph
    # A graph no process has joined yet holds no node but the grader's: nothing to ignore, and the grader's
    # participant may open while this node boots (RosSession opens on first use; issue 36)
    before = set(graph.node_names()) if getattr(graph, "peers_started", 1) else set()
    proc = s.launch(path, label or path.name, list(args), graph=graph)

    def again() -> LearnerProcess:
        """A fresh instance, once its node is up and spinning (a second Ctrl+C run, :func:`sigint_exit`); one
        that exits before its node appears is returned all the same, and judged (it did not keep running)."""
        def up() -> bool:
            return any(f"/{n}" in graph.node_names() for n in (node, *aliases))

        wait_until(lambda: not up(), 3.0, interval=0.05)  # the first instance's node has left the graph
        fresh = s.launch(path, (label or path.name) + ".again", list(args), graph=graph)
        if wait_until(up, timeout, interval=0.05, abort=lambda: fresh.poll() is not None):
            time.sleep(SETTLE)
        return fresh

    if sigint_check is not None:
        s.on_close(lambda: sigint_exit(s, sigint_check, proc, again=again))
    found = wait_for_node(s, check_id, proc, node, timeout=timeout, grace=grace, before=before, graph=graph,
                          aliases=aliases)
    if found:
        names = set(graph.node_names())
        return StartedNode(proc, next((n for n in (node, *aliases) if f"/{n}" in names), node), True)
    if proc.poll() is not None:
        raise Unmet(process_state(proc))
    plain = [n for n in graph.node_names() if n not in before and n.count("/") == 1]
    started = StartedNode(proc, plain[0].lstrip("/") if len(plain) == 1 else None, False)
    if started.name is None and need_node:
        raise Unmet(f"no node to inspect: {s.results[check_id].observed}")
    return started


def wait_for_node(s: Session, check_id: str, proc: LearnerProcess, node: str, timeout: float = 10.0,
                  grace: float = 3.0, before: Iterable[str] = (), graph: Any = None,
                  aliases: Iterable[str] = ()) -> bool:
    """Record ``check_id`` on whether a node called ``node`` appears within ``timeout`` seconds.

    ``aliases`` are other names accepted as that node: where the tutorial's own
    listing and its text disagree (its C++ listing names the node
    ``print_forever_cpp``, its printed log ``print_forever_node``), code typed as
    the tutorial gives it must not lose the points (issue 19).

    Stops waiting early if the process dies, or ``grace`` seconds after other
    nodes appeared without it (a misnamed node will not rename itself).
    Nodes named in ``before`` (those in the graph before ``proc`` started)
    are ignored: a node stopped a moment ago can linger in the graph until
    its DDS participant's lease expires. Observed lists the (new) nodes seen.
    """
    graph = graph or s.graph
    ignored = set(before)
    first_other: list[float] = []

    def new_nodes() -> list[str]:
        return [n for n in graph.node_names() if n not in ignored]

    def give_up() -> bool:
        if proc.poll() is not None:
            return True
        if not first_other and new_nodes():
            first_other.append(time.monotonic())
        return bool(first_other) and time.monotonic() - first_other[0] > grace

    accepted = [f"/{name}" for name in (node, *aliases)]
    begin = time.monotonic()
    with s.phase("start"):
        found = wait_until(lambda: any(name in new_nodes() for name in accepted), timeout, interval=0.05,
                           abort=give_up)
    waited = time.monotonic() - begin
    if found:
        name = next(name for name in accepted if name in new_nodes())
        also = f" (the tutorial's listing names it so; the lesson's name is {node})" if name != f"/{node}" else ""
        return s.record(check_id, True, f"node {name} is running{also}", f"a node named {node}")
    seen = ", ".join(new_nodes()) or "none"
    return s.record(check_id, False, f"no node named {node} after {waited:.1f} s; nodes seen: {seen}; "
                    f"{process_state(proc)}", f"a node named {node} (the name passed to super().__init__)")


#: Runs of one program whose Ctrl+C must all end in rclpy's shutdown race before :func:`sigint_exit` calls
#: the error the program's own (the race is about 1 % of presses, so a correct node fails 1 in 1,000,000).
RACE_RUNS = 3
_REPEATED = "runs in a row"  # the words of that verdict (the first run's note is not added to it)


def sigint_exit(s: Session, check_id: str, proc: LearnerProcess | ProgramRun,
                sigint_timeout: float = 3.0, again: Callable[[], LearnerProcess | None] | None = None, *,
                second_press: bool = True, races: int = 0) -> bool:
    """Press Ctrl+C (SIGINT) and record ``check_id``: exit code 0, no traceback, within ``sigint_timeout`` s.

    The kit's one Ctrl+C step (declared with :func:`ros2course.kit.checks.ctrl_c`).
    ``proc``: a running learner process (a node: Ctrl+C is pressed now), or a
    :class:`~ros2course.kit.programs.ProgramRun` that ``interrupt_after`` /
    ``scripts.run_script(..., interrupt_after_s=...)`` already ended with Ctrl+C
    (a script: judged as it ended, :func:`~ros2course.kit.programs.judge_interrupted_run`,
    which also fails a run whose started processes were still stopping).

    The rule is the tutorial's (ch. 13: a node ends cleanly on Ctrl+C; in
    Jazzy ``rclpy.spin()`` may raise ``ExternalShutdownException``). Observed
    says how long the exit took; fails for an exit code other than 0, a
    traceback, or a process still running (then stopped with SIGTERM /
    SIGKILL). Two allowances for races inside rclpy (Jazzy 7.1) that are not
    the learner's doing, measured here at about 1 % of SIGINTs each on nodes
    started the way the engine starts them (SIGINT ignored at exec, so only
    rclpy's handler reacts):

    * a node with nothing to wake it (no timer: a server, a subscriber) can
      miss the shutdown and keep waiting; if it still runs after half the
      timeout it gets a second Ctrl+C, as a user would press it again;
    * ``spin()`` / ``spin_once()`` can raise ``RCLError: ... context is not valid`` from inside
      rclpy's executor (:func:`~ros2course.run.process.rclpy_shutdown_race`) instead of ``ExternalShutdownException``. That exit
      says nothing about the program (one that catches only
      ``KeyboardInterrupt`` ends the same way in that run), so with ``again``
      (a callable that starts a fresh instance of the same program, running
      and ready for Ctrl+C, or returns None when none can be started at all:
      then as without ``again``) the fresh instance is judged instead, and
      observed says so (a fresh instance that exited before it was ready is
      judged too: it did not keep running until Ctrl+C, and counting the race
      as clean there once gave a program that catches nothing full marks, CI
      of stop 68: gazebo-custom-nodes ``thrust-ctrl-c-uncaught``); a fresh instance that hits it too gets
      another, and the same error in :data:`RACE_RUNS` runs in a row fails
      (a correct node: about 1 in 1,000,000 at the 1 % measured): then it
      is the program's, e.g. ``main()`` called twice (at import and by the
      entry point) spins the second time with rclpy's global executor,
      still bound to the context the first Ctrl+C shut down, and raises this
      very error on every run (sas held-out seed 28). Without ``again`` that
      exit counts as clean.

    The first press waits (at most 1 s) until the node's main thread is asleep, i.e. its executor waits
    (:meth:`~ros2course.run.process.LearnerProcess.wait_idle`): a Ctrl+C that lands while a callback runs
    ends ``spin()`` with no ``ExternalShutdownException``, so a node that catches only ``KeyboardInterrupt``
    passed in that run (CI of d9e731d, use-python-library ``humble-keyboardinterrupt-only``).

    A node that ignores Ctrl+C still fails (it ignores the second one too).
    A program that starts its node again after Ctrl+C (``main()`` called twice,
    e.g. once at import and once from the entry point) also ends only on the
    second press; with ``again``, a run that needed a second Ctrl+C is
    judged on a fresh instance that gets one press only (``second_press=False``),
    so the restarting program fails and a correct node fails only when rclpy
    misses the press in both runs (about 1 in 10,000 at the 1 % measured).
    Without ``again`` the second press still counts, as a user would press it.

    ``races``: how many runs before this one ended in the race (the fresh runs' own count; 0 from a grader).
    """
    if isinstance(proc, ProgramRun):
        return judge_interrupted_run(s, check_id, proc, sigint_timeout)
    expected = f"exit code 0 within {sigint_timeout:.0f} s of SIGINT (Ctrl+C), no traceback"
    if proc.poll() is not None:
        report = proc.stop()
        last = f": {report.traceback.strip().splitlines()[-1]}" if report.traceback.strip() else ""
        return s.record(check_id, False, f"the process had already exited (code {report.returncode}) before "
                        f"SIGINT{last}", expected, "the node must keep running until Ctrl+C")
    presses = 0
    with s.phase("stop"):
        proc.wait_idle()  # pressed while the node waits, as a person's Ctrl+C is (see LearnerProcess.wait_idle)
        begin = time.monotonic()
        for wait in ((sigint_timeout / 2, sigint_timeout / 2) if second_press else (sigint_timeout,)):
            presses += 1
            if not proc.interrupt():
                break
            if wait_until(lambda: proc.poll() is not None, wait, interval=0.01):
                break
        seconds = time.monotonic() - begin
        exited = proc.poll() is not None
        report = proc.stop(sigint_timeout=0.1, sigterm_timeout=2.0)
    twice = " (after a second Ctrl+C: rclpy missed the first one)" if presses > 1 else ""
    if not exited:
        return s.record(check_id, False,
                        f"still running {sigint_timeout:.0f} s after SIGINT (sent {'twice' if second_press else 'once'}"
                        f"); stopped with {report.signal_used or 'SIGKILL'}", expected,
                        "don't swallow Ctrl+C in a loop: let rclpy.spin() return and exit main()" if second_press else
                        "one Ctrl+C must end the program: don't start the node again after it (is main() called "
                        "twice, once at import and once by the entry point?), and don't swallow it in a loop")
    if report.traceback:
        last = report.traceback.strip().splitlines()[-1]
        if report.returncode != 0 and rclpy_shutdown_race(report.traceback):
            fresh = again() if again is not None and races + 1 < RACE_RUNS else None
            if fresh is not None:  # judge a run whose exit says something about the program
                passed = sigint_exit(s, check_id, fresh, sigint_timeout, again, races=races + 1)
                if check_id in s.results and races == 0 and _REPEATED not in s.results[check_id].observed:
                    s.amend(check_id, observed=f"{s.results[check_id].observed} (a second run: the first Ctrl+C "
                            "ended in rclpy's own shutdown race, an error raised inside rclpy itself, which says nothing "
                            "about your code)")
                return passed
            if races:  # the same error in every fresh run: no race, the program's own doing
                return s.record(check_id, False, f"exit code {report.returncode} with a traceback in {races + 1} "
                                f"{_REPEATED}: {last}", expected,
                                "rclpy was used after its context was shut down: is main() called twice (at import, "
                                "with no `if __name__ == '__main__':` guard, and again by the entry point)? rclpy's "
                                "global executor (rclpy.spin, rclpy.spin_once) keeps the first, shut-down context")
            return s.record(check_id, True, f"exit code {report.returncode}, {seconds:.2f} s after SIGINT{twice}, "
                            "with rclpy's own shutdown race (an error raised inside rclpy itself: not your code)", expected)
        return s.record(check_id, False, f"exit code {report.returncode} with a traceback: {last}", expected)
    if report.returncode != 0:
        return s.record(check_id, False, f"exit code {report.returncode} after SIGINT", expected)
    if presses > 1 and again is not None:
        fresh = again()
        if fresh is not None:  # rclpy missed the first press, or the program started its node again: one press now
            passed = sigint_exit(s, check_id, fresh, sigint_timeout, second_press=False)
            if check_id in s.results:
                s.amend(check_id, observed=f"{s.results[check_id].observed} (a second run, given one Ctrl+C: the "
                        "first run ended only after a second Ctrl+C)")
            return passed
    return s.record(check_id, True, f"exit code 0, {seconds:.2f} s after SIGINT{twice}", expected)


def ctrl_c_once_it_logs(s: Session, check_id: str, launch: Callable[[str], LearnerProcess], node: str, *,
                        patience: float) -> LearnerProcess:
    """Start a program that waits for something missing from the graph, and judge its Ctrl+C as the part ends.

    ``launch(suffix)`` starts the program (``suffix``: "" for the first run, ".again" for a fresh one) and returns
    its process. Waits until ``node``'s logger has written one more ``/rosout`` record than before the start
    (that it waits: what a learner sees before pressing Ctrl+C), at most ``patience`` seconds, or until the
    process ends; then registers :func:`sigint_exit` for ``check_id`` on the part's close, with ``again`` = the
    same start (a fresh run after rclpy's own shutdown race). Returns the first run's process.

    The tutorial's rule (ch. 13: a node ends cleanly on Ctrl+C), for a client or a node blocked in a wait
    loop (the action client, the Gazebo and Nav2 nodes, issue 37: their Ctrl+C while they wait).
    """
    rosout = s.graph.rosout()

    def start(suffix: str) -> LearnerProcess:
        before = len(rosout.records(node=node))
        proc = launch(suffix)
        with s.phase("observe"):
            wait_until(lambda: len(rosout.records(node=node)) > before, patience,
                       abort=lambda: proc.poll() is not None)
        return proc

    first = start("")
    s.on_close(lambda: sigint_exit(s, check_id, first, again=lambda: start(".again")))
    return first
