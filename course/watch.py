"""``ros2course watch``: re-check the current lesson whenever one of its files is saved.

The loop rustlings' ``watch`` made the norm: save, see the verdict, press a
key for a hint or the next lesson. File events come from watchfiles (Rust's
notify; inotify here) on the lesson's own paths (:attr:`Lesson.workspace_paths`),
debounced, with build output, logs and caches ignored. Each check runs as a
child ``ros2course check`` in its own session: a learner's node that hangs or
floods output is bounded by the check's own deadlines, the watcher stays
responsive to keys meanwhile, and quitting (``q`` or Ctrl+C) kills the child's
whole process group, so nothing is left running.

Keys (read one at a time from a terminal in cbreak mode): ``h`` next hint,
``n`` next lesson once this one has full marks, ``l`` list, ``c`` check now,
``q`` quit.
"""

from __future__ import annotations

import contextlib
import os
import queue
import select
import signal
import subprocess
import sys
import termios
import threading
import time
import tty
from collections.abc import Iterator
from pathlib import Path

import watchfiles
from rich.console import Console
from rich.rule import Rule

from ros2course.errors import CourseError
from ros2course.lesson.catalog import Catalog, Lesson
from ros2course.lesson.workspace import Workspace
from ros2course.run.process import kill_marked

#: Milliseconds watchfiles waits for more changes before reporting a batch (an editor's save is several events).
DEBOUNCE_MS = 400
#: Folders whose changes never trigger a check: colcon's output, the course's state, caches, build trees of
#: the CMake and pip lessons (the graders write there themselves).
IGNORED_DIRS = ("build", "install", "log", ".ros2course", "prefix", "dist")
#: Environment variable carrying the watcher's marker into its child checks (see :func:`kill_marked`).
MARKER_VAR = "ROS2COURSE_WATCH_MARKER"
#: Seconds a whole child check may take before the watcher stops it (its own deadlines come first).
CHECK_TIMEOUT = 900.0
KEYS = "h hint · n next lesson · l list · c check now · q quit"


class LessonFilter(watchfiles.DefaultFilter):
    """watchfiles' default filter (editor swap files, ``__pycache__``, ``.git``) plus :data:`IGNORED_DIRS` and
    ``*.egg-info`` (pip and colcon write them inside a learner's package)."""

    def __init__(self) -> None:
        super().__init__(ignore_dirs=(*watchfiles.DefaultFilter.ignore_dirs, *IGNORED_DIRS),
                         ignore_entity_patterns=(*watchfiles.DefaultFilter.ignore_entity_patterns, r"\.egg-info$"))


def watched_paths(lesson: Lesson, root: Path) -> list[Path]:
    """The existing paths to watch for ``lesson`` in the workspace ``root``.

    Its :attr:`~Lesson.workspace_paths` that exist; when none exists yet, the
    nearest existing folder above each (``src/`` before the package is made).
    """
    paths: list[Path] = []
    for relative in lesson.workspace_paths or ["src"]:
        path = root / relative
        while not path.exists() and path != root:
            path = path.parent
        if path not in paths:
            paths.append(path)
    return paths


class FileEvents:
    """A background thread turning watchfiles' change batches into a queue of changed paths.

    Args:
        paths: folders/files to watch (recursively).
    """

    def __init__(self, paths: list[Path]) -> None:
        self.paths = paths
        self.changes: queue.Queue[set[str]] = queue.Queue()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True, name="ros2course-watch")
        self._thread.start()

    def _run(self) -> None:
        for batch in watchfiles.watch(*self.paths, watch_filter=LessonFilter(), debounce=DEBOUNCE_MS,
                                      stop_event=self._stop, rust_timeout=200, yield_on_timeout=False,
                                      raise_interrupt=False):
            self.changes.put({path for _, path in batch})

    def pending(self) -> set[str]:
        """Every path changed since the last call (empty when none)."""
        out: set[str] = set()
        with contextlib.suppress(queue.Empty):
            while True:
                out |= self.changes.get_nowait()
        return out

    def close(self) -> None:
        """Stop the thread (within watchfiles' 200 ms poll)."""
        self._stop.set()
        self._thread.join(timeout=2.0)


@contextlib.contextmanager
def keypresses() -> Iterator[callable]:
    """Yield ``read(timeout) -> str | None``: one key from a terminal stdin in cbreak mode, restored on exit.

    With a stdin that is not a terminal, ``read`` only sleeps (no keys; Ctrl+C still quits).
    """
    stream = sys.stdin
    if not stream.isatty():
        def read_nothing(timeout: float) -> str | None:
            time.sleep(timeout)
            return None
        yield read_nothing
        return
    fd = stream.fileno()
    saved = termios.tcgetattr(fd)
    tty.setcbreak(fd)

    def read(timeout: float) -> str | None:
        ready, _, _ = select.select([fd], [], [], timeout)
        return os.read(fd, 1).decode(errors="replace") if ready else None

    try:
        yield read
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, saved)


class Watcher:
    """The watch loop for one workspace.

    Args:
        ws: an initialised workspace with a current lesson (``next`` sets it).
        catalog: the course.
        console: where verdicts and key output go.
    """

    def __init__(self, ws: Workspace, catalog: Catalog, console: Console) -> None:
        self.ws = ws
        self.catalog = catalog
        self.console = console
        self._child: subprocess.Popen | None = None
        #: inherited by the child check and every node it starts: see :meth:`_stop_child`
        self._marker = f"watch-{os.getpid()}-{time.monotonic_ns()}"

    def lesson(self) -> Lesson:
        """The current lesson of the progress file.

        Raises:
            CourseError: no current lesson (``next`` has never run).
        """
        current = self.ws.load_progress().current
        if current is None:
            raise CourseError("no current lesson to watch", "run 'ros2course next' first")
        return self.catalog.get(current)

    def run(self) -> int:
        """Check now, then on every save, until ``q`` or Ctrl+C; returns the exit status (0)."""
        lesson = self.lesson()
        events = FileEvents(watched_paths(lesson, self.ws.root))
        try:
            with keypresses() as read_key:
                quit_now = self._check(lesson, read_key, events.paths)
                while not quit_now:
                    key = read_key(0.1)
                    changed = events.pending()
                    if key == "q":
                        break
                    if key == "n":
                        moved = self._next(lesson)
                        if moved is not None:  # its instructions stay on screen: the first save checks it
                            lesson = moved
                            events.close()
                            events = FileEvents(watched_paths(lesson, self.ws.root))
                            self.console.print(Rule(f"watching {lesson.id}"))
                            self.console.print(f"[dim]save a file of it (or press c) to check · {KEYS}[/]")
                    elif key == "h":
                        self._command("hint", lesson.id)
                    elif key == "l":
                        self._command("list")
                    elif key == "c" or changed:
                        if changed:
                            names = sorted(os.path.relpath(p, self.ws.root) for p in changed)
                            self.console.print(f"[dim]changed: {', '.join(names[:5])}[/]")
                        quit_now = self._check(lesson, read_key, events.paths)
        except KeyboardInterrupt:
            pass
        finally:
            self._stop_child()
            events.close()
        self.console.print("[dim]watch ended[/]")
        return 0

    def _check(self, lesson: Lesson, read_key, paths: list[Path]) -> bool:
        """Grade ``lesson`` in a child process, showing its verdict in place; True when ``q`` was pressed meanwhile."""
        self.console.clear()
        self.console.print(Rule(f"watching {lesson.id}"))
        self.console.print(f"[dim]{', '.join(os.path.relpath(p, self.ws.root) for p in paths)} · {KEYS}[/]")
        self.console.print(f"[dim]{time.strftime('%H:%M:%S')} checking ...[/]")
        self._child = self._spawn("check", lesson.id)
        output: list[str] = []
        # read while it runs: a full pipe would block the child
        reader = threading.Thread(target=lambda: output.extend(self._child.stdout), daemon=True)
        reader.start()
        begin = time.monotonic()
        quit_asked = False
        while self._child.poll() is None:
            key = read_key(0.1)
            if key == "q":
                quit_asked = True
                break
            if time.monotonic() - begin > CHECK_TIMEOUT:
                self.console.print(f"[red]the check took more than {CHECK_TIMEOUT:.0f} s and was stopped[/]")
                break
        if self._child.poll() is None:
            self._stop_child()
            return quit_asked
        reader.join(timeout=5.0)
        self._child = None
        self.console.print("".join(output), end="", markup=False, highlight=False)
        self.console.print(f"[dim]{KEYS}[/]")
        return False

    def _next(self, lesson: Lesson) -> Lesson | None:
        """Move on once ``lesson`` has full marks (``ros2course next``); the new lesson, or None."""
        if self.ws.load_progress().status(lesson.id) != "done":
            self.console.print(f"[yellow]{lesson.id} has not had full marks yet: 'n' moves on once it has[/]")
            return None
        self._command("next")
        moved = self.lesson()
        return moved if moved.id != lesson.id else None

    def _command(self, *args: str) -> None:
        """Run another ``ros2course`` command (hint, list, next) and print its output."""
        child = self._spawn(*args)
        out, _ = child.communicate(timeout=60)
        self.console.print(out, end="", markup=False, highlight=False)

    def _spawn(self, *args: str) -> subprocess.Popen:
        env = {**os.environ, "COLUMNS": str(self.console.width), MARKER_VAR: self._marker}
        if self.console.is_terminal:
            env["FORCE_COLOR"] = "1"
        return subprocess.Popen([sys.executable, "-m", "ros2course", *args, "--workspace", str(self.ws.root)],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                text=True, env=env, cwd=self.ws.root, start_new_session=True)

    def _stop_child(self) -> None:
        """SIGINT, then SIGKILL, the running check's whole process group (its nodes stop with it)."""
        child, self._child = self._child, None
        if child is None or child.poll() is not None:
            return
        for sig, wait in ((signal.SIGINT, 5.0), (signal.SIGKILL, 5.0)):
            with contextlib.suppress(ProcessLookupError):
                os.killpg(child.pid, sig)
            with contextlib.suppress(subprocess.TimeoutExpired):
                child.wait(wait)
                break
        # learner nodes live in process groups of their own; a check killed before its cleanup
        # leaves them to this sweep of everything that inherited the watcher's marker
        kill_marked(self._marker, var=MARKER_VAR)
