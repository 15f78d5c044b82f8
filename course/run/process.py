"""Learner processes: start with a deadline, capture output, tear down completely.

Rules (shared/ROS_ENV.md, "Running and stopping nodes"):

* Each learner executable runs in its own session / process group
  (``start_new_session=True``), like pexpect's ``setsid()``, so signals reach
  its children too.
* Teardown escalates the way ``launch`` does: SIGINT, then SIGTERM, then
  SIGKILL, each to the whole group.
* A child that left the group (``setsid`` + double fork) is still found: every
  learner process carries a per-run marker in its environment, and after
  teardown every process still carrying it is killed (psutil reads environ).
* stdout/stderr are drained by threads into log files with a byte cap, so a
  node that floods its output neither blocks on a full pipe nor fills the disk.
* Fast DDS shared-memory files of processes that died without cleaning up are
  removed only when stale: their ``_el`` lock can be taken (ROS_ENV.md).
"""

from __future__ import annotations

import contextlib
import dataclasses
import fcntl
import functools
import os
import re
import shutil
import signal
import subprocess
import threading
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import psutil

from ros2course import sandbox

#: Environment variable carrying the per-run marker (see module docstring).
MARKER_VAR = "ROS2COURSE_RUN_MARKER"
#: Default cap of captured output per stream, bytes.
DEFAULT_OUTPUT_CAP = 2_000_000
#: Default lifetime of a learner process, seconds: past it the group is killed
#: even if the grader never got to stop it.
DEFAULT_DEADLINE = 120.0
_TAIL_BYTES = 64_000


@functools.cache
def default_sigint_prefix() -> tuple[str, ...]:
    """The command prefix that execs a program with SIGINT at its default action: ``(env, --default-signal=INT)``.

    GNU coreutils' ``env --default-signal`` (coreutils >= 8.31: Debian 12, Ubuntu 24.04) resets
    the signal's disposition and execs, so the PID and exit code stay the program's. Empty when
    this machine's ``env`` lacks the option (probed once per process): the program then inherits
    ros2course's own disposition of SIGINT.
    """
    env = shutil.which("env") or "/usr/bin/env"
    try:
        works = subprocess.run([env, "--default-signal=INT", "true"], capture_output=True,  # noqa: S603
                               timeout=10, check=False).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        works = False
    return (env, "--default-signal=INT") if works else ()


@dataclasses.dataclass
class ExitReport:
    """How a learner process ended.

    Attributes:
        returncode: the exit code (negative: killed by that signal); None if it could not be reaped.
        signal_used: the last signal we had to send (``"SIGINT"``, ``"SIGTERM"``, ``"SIGKILL"``),
            or None when it had exited on its own.
        seconds: from the first signal (or the teardown call) to the exit, seconds.
        traceback: the last traceback printed on stderr/stdout, or "".
        left_running: when the process had already exited before :meth:`LearnerProcess.stop`,
            the processes it started that were still running then (``"<pid> <command line>"``,
            :func:`marked_processes`): a script that ended before its children had stopped.
    """

    returncode: int | None
    signal_used: str | None
    seconds: float
    traceback: str
    left_running: tuple[str, ...] = ()


class OutputDrain(threading.Thread):
    """Copy a pipe into a log file up to ``cap`` bytes, keep a tail in memory, count the rest."""

    def __init__(self, pipe, log_path: Path, cap: int) -> None:
        super().__init__(daemon=True, name=f"drain-{log_path.name}")
        self.pipe = pipe
        self.log_path = log_path
        self.cap = cap
        self.total = 0
        self.head = bytearray()
        self.tail = bytearray()
        self.lock = threading.Lock()

    def run(self) -> None:
        with open(self.log_path, "wb") as log:
            while True:
                try:
                    chunk = os.read(self.pipe.fileno(), 65536)
                except OSError:
                    break
                if not chunk:
                    break
                with self.lock:
                    room = self.cap - self.total
                    if room > 0:
                        log.write(chunk[:room])
                        log.flush()
                        if len(self.head) < _TAIL_BYTES:
                            self.head.extend(chunk[: _TAIL_BYTES - len(self.head)])
                    self.total += len(chunk)
                    self.tail.extend(chunk)
                    del self.tail[:-_TAIL_BYTES]
            if self.total > self.cap:
                log.write(f"\n[ros2course: output capped at {self.cap} bytes; {self.total - self.cap} more bytes dropped]\n".encode())
        with contextlib.suppress(OSError):
            self.pipe.close()

    def text(self) -> str:
        """The head and tail of what was captured (joined when both fit)."""
        with self.lock:
            if self.total <= _TAIL_BYTES:
                return bytes(self.tail).decode(errors="replace")
            return (bytes(self.head).decode(errors="replace") + "\n[...]\n" + bytes(self.tail).decode(errors="replace"))


#: The prefix ``ros2 launch`` puts on each line a launched process prints (``[talker-1] ``: its executable's name,
#: a dash and its process number; launch's ``launch.actions.ExecuteProcess`` output handlers).
_LAUNCH_PREFIX = re.compile(r"^\[([^\]\s]+-\d+)\] ?")


def last_traceback(text: str) -> str:
    """The last Python traceback (or C++ terminate message) in ``text``, or "".

    Only the traceback itself: from ``Traceback (most recent call last):``
    through its indented frames to the exception line (``ValueError: ...``),
    or from ``terminate called after throwing ...`` through its indented
    ``what():`` line. Output printed after it (the other stream, a later
    ``print``) is not part of it. Formats: CPython's ``traceback`` module,
    libstdc++'s verbose terminate handler. A traceback a process printed
    under ``ros2 launch`` has each line prefixed with ``[<name>-<n>] ``;
    it is read from that process's lines only (another process's lines may
    interleave), with the prefix removed, so its exception line is found
    (CI, stop 65: a launched node's traceback was cut at its first frame,
    and rclpy's own shutdown race in it was taken for the learner's).
    """
    for marker, ends_with_unindented in (("Traceback (most recent call last):", True),
                                         ("terminate called after throwing", False)):
        index = text.rfind(marker)
        if index < 0:
            continue
        start = text.rfind("\n", 0, index) + 1
        launched = _LAUNCH_PREFIX.match(text[start:index])
        if launched and text[start:index] == launched.group(0):
            tag = launched.group(1)
            rest = [_LAUNCH_PREFIX.sub("", line, count=1) for line in text[index:].splitlines()[1:]
                    if (m := _LAUNCH_PREFIX.match(line)) and m.group(1) == tag]
        else:
            rest = text[index:].splitlines()[1:]
        first = text[index:].splitlines()[0]
        kept = [first]
        for line in rest:
            if line[:1] in (" ", "\t"):
                kept.append(line)
            elif ends_with_unindented and line.strip():
                kept.append(line)  # the exception line ends a Python traceback
                break
            else:
                break
        return "\n".join(kept).strip()
    return ""


def rclpy_shutdown_race(trace: str) -> bool:
    """Whether ``trace`` (a traceback, :func:`last_traceback`) is rclpy's own Ctrl+C race, not the program's.

    A SIGINT that lands while Jazzy's rclpy (7.1) executor prepares a wait
    can make ``rclpy.spin()`` / ``rclpy.spin_once()`` raise
    ``RCLError: ... the given context is not valid``, even in a node that
    catches ``KeyboardInterrupt`` and ``ExternalShutdownException`` (a known
    shutdown race, discussed in ros2/ros2cli PR #854). Two places are known:
    the wait set (``failed to initialize wait set``, raised in
    ``rclpy/executors.py``) and the timeout timer that
    ``Executor._wait_for_ready_callbacks`` makes for ``spin_once(timeout_sec=)``
    (``failed to create timer``, raised in ``rclpy/timer.py`` called from
    ``rclpy/executors.py``; CI of stop 66: the actions-client reference).

    The same shutdown can land while the executor runs one of the program's
    callbacks, whose next rclpy call (a publish, a timer it makes) raises
    ``RCLError: ... context is invalid`` from inside rclpy. And it can land
    between two ``rclpy.spin_once()`` calls of a wait loop: the shutdown
    resets rclpy's global executor, and the next call's
    ``get_global_executor()`` returns None on the shut-down context
    (``AttributeError: 'NoneType' object has no attribute 'add_node'``,
    raised in ``rclpy/__init__.py``): rclpy's too.

    True when the exception is that RCLError, raised inside the ``rclpy``
    package (its last frame), while the executor was running (a frame in
    ``rclpy/executors.py``), or that AttributeError raised in
    ``rclpy/__init__.py`` itself. A program that calls rclpy after its own
    ``rclpy.shutdown()`` in ``main`` (no executor frame) is not matched. A
    check that can start the program again (``kit.nodes.sigint_exit``'s
    ``again``) judges a fresh run instead, so a program whose own callback
    really fails this way fails there, and so does a program that raises it
    on every run (``main()`` called twice spins rclpy's global executor,
    still bound to the context the first Ctrl+C shut down: the same error,
    every time; ``sigint_exit`` fails it after ``RACE_RUNS`` runs in a row).
    """
    lines = [line for line in trace.strip().splitlines() if line.strip()]
    frames = [line for line in lines if line.lstrip().startswith('File "')]
    last = lines[-1] if lines else ""
    if frames and "/rclpy/__init__.py" in frames[-1] and last.endswith(_NO_GLOBAL_EXECUTOR):
        return True
    return (bool(frames) and "/rclpy/" in frames[-1] and any("/rclpy/executors.py" in f for f in frames)
            and "RCLError" in last and ("context is not valid" in last or "context is invalid" in last))


#: The last line of rclpy's third shutdown race (Jazzy 7.1, ``rclpy/__init__.py``): Ctrl+C lands between two
#: ``rclpy.spin_once()`` calls; the shutdown resets the global executor to None, and the next call's
#: ``get_global_executor()`` makes a new one whose ``context.on_shutdown(reset_executor)`` runs at once on the
#: shut-down context, so it returns None and ``executor.add_node(node)`` raises (gazebo-custom-nodes' reference,
#: 1 run in 20 at load 2, stop 69).
_NO_GLOBAL_EXECUTOR = "AttributeError: 'NoneType' object has no attribute 'add_node'"


#: A ROS log line at ERROR or FATAL severity as rcutils prints it (``[ERROR] [1732000000.1] [node]: text``).
_ERROR_RECORD = re.compile(r"^\[(ERROR|FATAL)\] \[[0-9.]+\] \[[^\]]*\]: .*$", re.MULTILINE)


def last_error_record(text: str) -> str:
    """The last ERROR or FATAL log line in ``text`` (rcutils' console format, ``RCUTILS_CONSOLE_OUTPUT_FORMAT``
    default ``[{severity}] [{time}] [{name}]: {message}``), or ""."""
    found = [m.group(0) for m in _ERROR_RECORD.finditer(text)]
    return found[-1].strip() if found else ""


@dataclasses.dataclass(frozen=True)
class ProcessExit:
    """How a learner process ended before the grader stopped it: the one account of a process's end that
    ``kit.process_state`` (the observed text) and the engine's ``process`` diagnosis both use (issue 19).

    Attributes:
        returncode: the exit code; negative when a signal killed it (``Popen.returncode``'s convention).
        seconds: from start to exit, seconds (measured by a thread waiting on the process); None if unknown.
        last_line: the last traceback line (``ValueError: ...``), else the last ERROR/FATAL log line,
            else the last line of stderr; "" when it printed nothing.
    """

    returncode: int
    seconds: float | None
    last_line: str

    @property
    def signal_name(self) -> str | None:
        """``SIGSEGV`` for a process a signal killed, else None."""
        if self.returncode >= 0:
            return None
        try:
            return signal.Signals(-self.returncode).name
        except ValueError:
            return f"signal {-self.returncode}"

    def describe(self) -> str:
        """``exited with code 1 after 0.3 s`` or ``was killed by SIGSEGV after 2.1 s`` (no last line)."""
        after = f" after {self.seconds:.1f} s" if self.seconds is not None else ""
        if self.signal_name is not None:
            return f"was killed by {self.signal_name}{after}"
        return f"exited with code {self.returncode}{after}"


class LearnerProcess:
    """One learner executable, started in its own process group.

    Args:
        argv: the command (``argv[0]`` an absolute path to the executable).
        env: its complete environment (the marker is added).
        log_dir: where ``<name>.stdout.log`` / ``<name>.stderr.log`` go.
        name: a short label for logs and messages (e.g. the executable name).
        output_cap: bytes kept per stream in the log file.
        cwd: working directory (default: ``log_dir``).
        ros_sigint: start it with SIGINT ignored at exec (as ``node &`` from a
            shell script is). Python then installs no ``KeyboardInterrupt``
            handler and only rclpy's own SIGINT handler reacts, which in Jazzy
            makes ``rclpy.spin()`` raise ``ExternalShutdownException``. That is
            the case shared/LESSONS.md requires learners to handle; with the
            default disposition whether KeyboardInterrupt or the exception
            wins is a race, so the verdict would not be deterministic. rclpy
            and rclcpp install their handlers regardless, so nodes still stop.
        deadline: seconds after start when a watchdog SIGKILLs the group and
            the marked processes, whatever the grader is doing (None: never).
        stdin_open: its stdin is a pipe kept open and never written, as a terminal nobody types into: a
            program that asks a question (``ssh-keygen`` without ``-N ''`` asks for a passphrase) waits for an
            answer until it is stopped. Default: ``/dev/null``, where such a question reads an empty answer at
            once (end of file).
    """

    def __init__(self, argv: list[str], env: dict[str, str], log_dir: Path, name: str,
                 output_cap: int = DEFAULT_OUTPUT_CAP, cwd: Path | None = None, ros_sigint: bool = False,
                 deadline: float | None = DEFAULT_DEADLINE, stdin_open: bool = False) -> None:
        # sh's `trap '' INT` sets SIGINT to ignored and exec keeps that (POSIX); util-linux's
        # setpriv sets the parent-death signal, so the node dies even if ros2course is
        # SIGKILLed. Both exec into the learner's program (same PID); no preexec_fn, which is
        # unsafe in a process with threads (the executor's).
        # Otherwise SIGINT starts at its default action, as in a terminal, even when ros2course
        # itself was started with it ignored (a background job of a script, `cmd &`, inherits
        # SIGINT ignored, and exec keeps an ignored signal): a program, a bash script or a node
        # that ignores Ctrl+C only because its grader was started that way would lose its
        # Ctrl+C check. A shell cannot undo that (POSIX: signals ignored on entry to a
        # non-interactive shell cannot be reset); GNU env's --default-signal can, and execs.
        if ros_sigint:
            wrapped = ["/bin/sh", "-c", "trap '' INT; exec \"$0\" \"$@\"", *argv]
        else:
            wrapped = [*default_sigint_prefix(), *argv]
        # The kernel sends the parent-death signal when the *thread* that forked the child
        # ends (prctl(2)), so it is only safe from the main thread.
        main_thread = threading.current_thread() is threading.main_thread()
        self.name = name
        self.marker = uuid.uuid4().hex
        self.env = {**env, MARKER_VAR: self.marker}
        # In batch grading the submission's own uid runs it (ros2course.sandbox); the
        # drop and the parent-death signal are then set by one setpriv.
        if sandbox.current() is not None:
            self.argv, self._popen_env = sandbox.command(wrapped, self.env, pdeathsig=main_thread)
        else:
            self.argv = [*(sandbox.die_with_parent() if main_thread else []), *wrapped]
            self._popen_env = self.env
        self.log_dir = log_dir
        self.output_cap = output_cap
        self.cwd = cwd or log_dir
        self.popen: subprocess.Popen | None = None
        self.stdin_open = stdin_open
        self.started_at = 0.0
        self._drains: list[OutputDrain] = []
        self.report: ExitReport | None = None
        self.deadline = deadline
        self.deadline_hit = False
        self._watchdog: threading.Timer | None = None
        #: the learner's own program (``argv[0]`` before any wrapper): the executable the grader found.
        self.program = Path(argv[0]) if argv else Path()
        #: ``time.monotonic()`` when the process exited (set by a thread waiting on it), else None.
        self.ended_at: float | None = None
        #: ``time.monotonic()`` of the first signal the grader sent it (:meth:`interrupt`, :meth:`stop`), else None.
        self.signalled_at: float | None = None

    @property
    def stdout_log(self) -> Path:
        return self.log_dir / f"{self.name}.stdout.log"

    @property
    def stderr_log(self) -> Path:
        return self.log_dir / f"{self.name}.stderr.log"

    def start(self) -> LearnerProcess:
        """Start the process (raises OSError if the executable cannot be run)."""
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.started_at = time.monotonic()
        self.popen = subprocess.Popen(  # noqa: S603 - runs the learner's own executable, by design
            self.argv, env=self._popen_env, cwd=self.cwd, stdin=subprocess.PIPE if self.stdin_open else subprocess.DEVNULL,
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
        self._drains = [OutputDrain(self.popen.stdout, self.stdout_log, self.output_cap),
                        OutputDrain(self.popen.stderr, self.stderr_log, self.output_cap)]
        for drain in self._drains:
            drain.start()
        # The exit time of a process that dies on its own (``exited after 0.3 s``), noted by a thread
        # of its own that waits without reaping (see _await_exit).
        threading.Thread(target=self._await_exit, daemon=True, name=f"ros2course-wait-{self.name}").start()
        if self.deadline is not None:
            self._watchdog = threading.Timer(self.deadline, self._on_deadline)
            self._watchdog.daemon = True
            self._watchdog.start()
        return self

    def _await_exit(self) -> None:
        """Note when the process exits, without reaping it: ``waitid(P_PID, pid, WEXITED | WNOWAIT)``.

        The zombie keeps its pid, and so the id of its process group, until :meth:`poll` or
        :meth:`stop` collects it: a pid reaped early could be reused by a new process group
        (pid_max is 32768 on many hosts) that stop()'s final SIGKILL to the group would hit.
        """
        assert self.popen is not None
        with contextlib.suppress(ChildProcessError, OSError):  # already reaped by poll(): the time is near enough
            os.waitid(os.P_PID, self.popen.pid, os.WEXITED | os.WNOWAIT)
        self.ended_at = time.monotonic()

    def exit_state(self) -> ProcessExit | None:
        """How the process ended, or None while it runs (or before :meth:`start`).

        ``seconds`` is from start to exit; ``last_line`` from its output (:class:`ProcessExit`).
        """
        code = self.poll()
        if code is None:
            return None
        ended = self.ended_at
        if ended is None:  # the waiting thread has not woken yet: reaped by poll() just now
            ended = time.monotonic()
        text_err, text_out = self.stderr(), self.stdout()
        trace = last_traceback(text_err) or last_traceback(text_out)
        if trace:
            last = trace.strip().splitlines()[-1].strip()
        else:
            last = (last_error_record(text_err) or last_error_record(text_out)
                    or (text_err.strip().splitlines() or [""])[-1].strip())
        return ProcessExit(code, ended - self.started_at if self.started_at else None, last)

    def exited_on_its_own(self) -> bool:
        """True once it exited before any signal of the grader (a crash, a ``main()`` that returned)."""
        if self.poll() is None or self.deadline_hit:
            return False
        return self.signalled_at is None or (self.ended_at is not None and self.ended_at < self.signalled_at)

    def interrupt(self) -> bool:
        """Send SIGINT (Ctrl+C) to its process group; False when the group is gone."""
        self.signalled_at = self.signalled_at or time.monotonic()
        try:
            os.killpg(self.pid, signal.SIGINT)
        except (ProcessLookupError, PermissionError):
            return False
        return True

    def wait_idle(self, timeout: float = 1.0, quiet: float = 0.005, interval: float = 0.001) -> bool:
        """Wait until the main thread of each of its processes has been asleep for ``quiet`` s in a row.

        ``timeout``, ``quiet``, ``interval``: seconds (at most, the quiet stretch, between two looks).
        Looks at the state of the main thread (``/proc/PID/task/PID/stat``: ``S`` or ``D``, asleep)
        of the process and of its descendants (a wrapper script, ``ros2 run``'s child), at most
        every ``interval``; True once every one was asleep at each look over ``quiet`` seconds,
        False after ``timeout`` (a program that never waits: the caller goes on all the same) or
        when the process is gone. Never raises.

        Why: rclpy (Jazzy 7.1, ``rclpy/executors.py``) raises ``ExternalShutdownException`` on Ctrl+C
        only when the shutdown finds the executor inside ``wait_set.wait()``; a Ctrl+C that lands while
        a callback runs ends ``spin()`` by its ``while context.ok()`` test, with no exception. A node
        that catches only ``KeyboardInterrupt`` (the Humble habit the lessons warn about) then exits
        cleanly in that run: pressed while the node waits, as a person's Ctrl+C almost always is
        (callbacks take milliseconds of each period), the verdict no longer depends on that luck
        (CI of d9e731d: use-python-library ``humble-keyboardinterrupt-only`` got full marks once).
        The main thread's sleep is what counts: rclpy's executor waits there, the DDS threads wake
        on their own schedules.
        """
        # psutil has no per-thread state, so the main thread's is read from /proc itself.
        def asleep(pid: int) -> bool:
            try:
                with open(f"/proc/{pid}/task/{pid}/stat", "rb") as handle:
                    stat = handle.read()
            except OSError:  # gone: it sleeps no more, and the caller finds it ended
                return True
            return stat[stat.rfind(b")") + 2:][:1] in (b"S", b"D")

        try:
            pids = [self.pid, *(child.pid for child in psutil.Process(self.pid).children(recursive=True))]
        except (psutil.Error, AssertionError):
            return False
        end = time.monotonic() + timeout
        since: float | None = None
        while time.monotonic() < end and self.poll() is None:
            now = time.monotonic()
            if all(asleep(pid) for pid in pids):
                since = now if since is None else since
                if now - since >= quiet:
                    return True
            else:
                since = None
            time.sleep(interval)
        return False

    def _on_deadline(self) -> None:
        if self.popen is not None and self.popen.poll() is None:
            self.deadline_hit = True
            self._signal_group(signal.SIGKILL)
            kill_marked(self.marker)

    @property
    def pid(self) -> int:
        assert self.popen is not None
        return self.popen.pid

    def poll(self) -> int | None:
        """The exit code if it has exited, else None."""
        return None if self.popen is None else self.popen.poll()

    def stdout(self) -> str:
        """Captured stdout (head and tail for long output)."""
        return self._drains[0].text() if self._drains else ""

    def stderr(self) -> str:
        """Captured stderr (head and tail for long output)."""
        return self._drains[1].text() if self._drains else ""

    def output_bytes(self) -> int:
        """Total bytes the process wrote on stdout and stderr (including dropped ones)."""
        return sum(d.total for d in self._drains)

    def _signal_group(self, sig: int) -> None:
        self.signalled_at = self.signalled_at or time.monotonic()
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.pid, sig)

    def _wait(self, timeout: float) -> bool:
        assert self.popen is not None
        try:
            self.popen.wait(timeout=max(timeout, 0.0))
            return True
        except subprocess.TimeoutExpired:
            return False

    def stop(self, sigint_timeout: float = 5.0, sigterm_timeout: float = 2.0) -> ExitReport:
        """End the process and everything it started; idempotent.

        SIGINT to the group, wait up to ``sigint_timeout`` s; SIGTERM, wait up to
        ``sigterm_timeout`` s; then SIGKILL. Whatever the main process did, the
        group and every process carrying this run's marker are SIGKILLed at the
        end, and stale Fast DDS shared-memory files are removed.
        """
        if self.report is not None:
            return self.report
        if self._watchdog is not None:
            self._watchdog.cancel()
        if self.popen is None:
            self.report = ExitReport(None, None, 0.0, "")
            return self.report
        begin = time.monotonic()
        signal_used = None
        left = marked_processes(self.marker) if self.popen.poll() is not None else []
        if self.popen.poll() is None:
            for sig, timeout in ((signal.SIGINT, sigint_timeout), (signal.SIGTERM, sigterm_timeout),
                                 (signal.SIGKILL, 5.0)):
                signal_used = sig.name
                self._signal_group(sig)
                if self._wait(timeout):
                    break
        seconds = time.monotonic() - begin
        self._signal_group(signal.SIGKILL)  # children left in the group
        kill_marked(self.marker)
        if self.popen.stdin is not None:  # stdin_open: the pipe's end kept for it
            with contextlib.suppress(OSError):
                self.popen.stdin.close()
        for drain in self._drains:
            drain.join(timeout=2.0)
        # Python writes tracebacks to stderr; stdout only when a program prints one itself
        trace = last_traceback(self.stderr()) or last_traceback(self.stdout())
        self.report = ExitReport(self.popen.poll(), signal_used, seconds, trace, tuple(left))
        return self.report

    def __enter__(self) -> LearnerProcess:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop(sigint_timeout=1.0, sigterm_timeout=1.0)
        sweep_stale_fastdds_shm()


def _marked(marker: str, var: str) -> Iterator[psutil.Process]:
    """Processes (this one excepted) whose environment (``/proc/PID/environ``) has ``var=marker``."""
    needle = f"{var}={marker}".encode()
    me = os.getpid()
    for proc in psutil.process_iter(["pid"]):
        if proc.pid == me:
            continue
        try:
            with open(f"/proc/{proc.pid}/environ", "rb") as handle:
                if needle in handle.read():
                    yield proc
        except OSError:
            continue


def marked_processes(marker: str, var: str = MARKER_VAR) -> list[str]:
    """Live processes (zombies and this one excepted) whose environment has ``var=marker``:
    ``"<pid> <command line>"`` each (command line cut at 200 characters), by PID."""
    found: list[str] = []
    for proc in _marked(marker, var):
        with contextlib.suppress(psutil.Error):
            if proc.status() != psutil.STATUS_ZOMBIE:
                found.append(f"{proc.pid} {' '.join(proc.cmdline())[:200]}")
    return found


def kill_marked(marker: str, var: str = MARKER_VAR) -> list[int]:
    """SIGKILL every process (but this one) whose environment has ``var=marker``; returns their PIDs.

    Catches learner children that escaped the process group (setsid, double fork).
    """
    killed: list[psutil.Process] = []
    for proc in _marked(marker, var):
        with contextlib.suppress(psutil.Error):
            proc.kill()
            killed.append(proc)
    # Our own children are reaped by their Popen.wait(): waiting here would reap them first
    # and Popen would report exit code 0 for a killed process.
    psutil.wait_procs([p for p in killed if _parent_pid(p) != os.getpid()], timeout=3)
    return [proc.pid for proc in killed]


def _parent_pid(proc: psutil.Process) -> int | None:
    try:
        return proc.ppid()
    except psutil.Error:
        return None


SHM_DIR = Path("/dev/shm")


#: Seconds a Fast DDS file must have existed before a sweep may judge it stale. A
#: participant creates a segment, then its ``_el`` lock file, then takes the lock;
#: a file younger than this may be half-way through that and is left for a second pass.
SHM_MIN_AGE = 1.0


def sweep_stale_fastdds_shm(shm_dir: Path = SHM_DIR, min_age: float = SHM_MIN_AGE,
                            wait: bool = True) -> list[str]:
    """Remove Fast DDS shared-memory files whose owners are gone; returns the names removed.

    A segment ``fastrtps_X`` has a lock file ``fastrtps_X_el`` that live users
    hold a shared ``flock`` on; when ``flock(LOCK_EX|LOCK_NB)`` succeeds nobody
    uses it and ``fastrtps_X``, ``fastrtps_X_el`` and ``sem.fastrtps_X_mutex``
    go. Files in use are never touched (shared/ROS_ENV.md).

    A ``fastrtps_*`` segment (or its ``sem.*_mutex``) left without any ``_el``
    lock file (a writer re-created a port whose listener had died) is removed
    only if no process maps it or holds it open (/proc/*/maps and /proc/*/fd).

    An unused file younger than ``min_age`` seconds is not removed: another
    participant (a check running beside this one) may be creating it and not
    hold its lock yet. With ``wait`` (the default), when such young files were
    seen the sweep waits ``min_age`` seconds once and sweeps again, so a node
    killed right after it started leaves nothing behind either.
    """
    removed, young = _sweep_once(shm_dir, min_age)
    if young and wait:
        time.sleep(min_age)
        removed += _sweep_once(shm_dir, min_age)[0]
    return removed


def _sweep_once(shm_dir: Path, min_age: float) -> tuple[list[str], bool]:
    """One pass of :func:`sweep_stale_fastdds_shm`: (names removed, whether unused young files were left)."""
    removed: list[str] = []
    young = False
    if not shm_dir.is_dir():
        return removed, young
    now = time.time()

    def too_young(path: Path) -> bool:
        nonlocal young
        try:
            info = path.stat()
        except FileNotFoundError:
            return False  # gone already: nothing to protect
        if now - min(info.st_mtime, info.st_ctime) < min_age:
            young = True
            return True
        return False

    orphans = [p for p in shm_dir.glob("fastrtps_*") if not p.name.endswith("_el")
               and not (shm_dir / f"{p.name}_el").exists()]
    orphans += [p for p in shm_dir.glob("sem.fastrtps_*_mutex")
                if not (shm_dir / f"{p.name[4:-len('_mutex')]}_el").exists()]
    if orphans:
        used = _shm_files_in_use(shm_dir)
        for path in orphans:
            if _shm_file_id(path) not in used and not too_young(path):
                with contextlib.suppress(FileNotFoundError):
                    path.unlink()
                    removed.append(path.name)
    for lock in shm_dir.glob("fastrtps_*_el"):
        base = lock.name[: -len("_el")]
        try:
            fd = os.open(lock, os.O_RDWR)
        except OSError:
            continue
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                continue  # in use
            if too_young(lock) or too_young(shm_dir / base):
                continue  # maybe not locked by its creator yet
            for name in (base, f"sem.{base}_mutex", lock.name):
                with contextlib.suppress(FileNotFoundError):
                    (shm_dir / name).unlink()
                    removed.append(name)
        finally:
            os.close(fd)
    return removed, young


def _shm_file_id(path: Path) -> tuple[int, int] | None:
    """``(st_dev, st_ino)`` of ``path``, or None when it is gone."""
    try:
        info = path.stat()
    except OSError:
        return None
    return info.st_dev, info.st_ino


def _shm_files_in_use(shm_dir: Path = SHM_DIR) -> set[tuple[int, int]]:
    """``(st_dev, st_ino)`` of the files under ``shm_dir`` that some process maps or holds open (as far as we may
    look). By device and inode, not by path: a process in another mount namespace (a submission graded with a
    private /dev/shm, ``ros2course.sandbox``) maps files of the same names that are other files (a check beside
    such a one kept its own orphaned ``fastrtps_port7000`` for one in use)."""
    prefix = str(shm_dir).rstrip("/") + "/"
    used: set[tuple[int, int]] = set()
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        with contextlib.suppress(OSError):
            with open(f"/proc/{pid}/maps", encoding="utf-8", errors="replace") as maps:
                for line in maps:
                    if prefix not in line:
                        continue
                    fields = line.split(maxsplit=5)  # address perms offset dev(major:minor, hex) inode path
                    with contextlib.suppress(ValueError, IndexError):
                        major, minor = (int(part, 16) for part in fields[3].split(":"))
                        used.add((os.makedev(major, minor), int(fields[4])))
        with contextlib.suppress(OSError):
            for fd in os.listdir(f"/proc/{pid}/fd"):
                with contextlib.suppress(OSError):
                    if os.readlink(f"/proc/{pid}/fd/{fd}").startswith(prefix):
                        info = os.stat(f"/proc/{pid}/fd/{fd}")  # the open file itself, whatever its namespace
                        used.add((info.st_dev, info.st_ino))
    return used
