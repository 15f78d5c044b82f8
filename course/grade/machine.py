"""The machine as one grading sees it: :class:`MachineView`, the learner's workspace, its environment and
the programs the grader starts in it.

The part of a grading session that touches the machine: the sourced workspace (``install/setup.bash``),
the ament index (``ros2 run``'s and ``ros2 launch``'s lookups), generated interface types, the course's
reference sources, folders a submission may write, and every process the grader starts as the
submission (:class:`~ros2course.run.process.LearnerProcess`, colcon through :mod:`ros2course.sandbox`).
It knows nothing of verdicts or ROS graphs: :class:`~ros2course.grade.session.GradingSession` composes
it with the verdict book (:mod:`ros2course.grade.verdicts`) and the observer, and gives a learner
node the graph's environment before it starts it here.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from ros2course import sandbox
from ros2course.builder import colcon as build_mod
from ros2course.errors import CourseError
from ros2course.lesson.catalog import Lesson
from ros2course.ros import index as ament_index
from ros2course.ros.interfaces import workspace_type
from ros2course.ros.manifests import find_packages
from ros2course.run.process import LearnerProcess


class MachineView:
    """One grading's view of the machine: the workspace, its environment, and the processes started in it.

    Args:
        lesson: the :class:`~ros2course.lesson.catalog.Lesson` (its declared ``interfaces`` and ``references``).
        workspace_root: the colcon workspace being graded (absolute).
        log_dir: the check's log folder; learner process logs and submission folders go here.
        base_env: the ROS install's environment (no workspace overlay, no domain id).
        trusted_interfaces: batch grading only: the course's own build of the lesson's interface and
            reference packages, used instead of the submission's (whose generated code would run in
            the grader).

    Attributes:
        processes: every process started through :meth:`process`, in order (stopped by :meth:`stop_processes`).
    """

    def __init__(self, lesson: Lesson, workspace_root: Path, log_dir: Path, base_env: dict[str, str],
                 trusted_interfaces: Path | None = None) -> None:
        self.lesson = lesson
        self.workspace_root = workspace_root
        self.log_dir = log_dir
        self.base_env = base_env
        self.trusted_interfaces = trusted_interfaces
        self.processes: list[LearnerProcess] = []
        self._tmpdir: Path | None = None
        self._tmpdir_lock = threading.Lock()  # a lesson's parts start processes from threads of their own
        self._overlay: dict[str, str] | None = None

    # --- the workspace -----------------------------------------------------------------------------

    def overlay(self) -> dict[str, str]:
        """The sourced workspace environment (``install/setup.bash`` over ``base_env``), without the domain id;
        a copy, read once per grading."""
        if self._overlay is None:
            self._overlay = build_mod.overlay_env(self.workspace_root, self.base_env)
        return dict(self._overlay)

    def interface_type(self, package: str, kind: str, name: str) -> Any:
        """A generated msg/srv class from the workspace (see :mod:`ros2course.ros.interfaces`).

        With ``trusted_interfaces`` (batch grading) the class comes from the course's own build of the
        package, never from the submission's: its generated Python and C code would run inside the grader.

        Raises:
            NotGradable: the interface package is not built or does not load.
            CourseError: the lesson does not declare ``package`` in ``interfaces:``, or submission code runs
                sandboxed and the course has no build of ``package``.
        """
        if package not in self.lesson.interfaces:
            # the same refusal under check and batch: an undeclared package fails dev validate, not a class
            raise CourseError(f"the grader of {self.lesson.id} imports {package} types but its lesson.yaml does not "
                              f"declare them", f"a fault of the course: add 'interfaces: [{package}]' to lesson.yaml")
        if self.trusted_interfaces is not None:
            return workspace_type(build_mod.overlay_env(self.trusted_interfaces, self.base_env), package, kind, name)
        if sandbox.current() is not None:
            raise CourseError(f"the grader needs {package} types but the batch built no trusted copy of {package}",
                              "a fault of the grading run: grade through ros2course grade, which builds them")
        return workspace_type(self.overlay(), package, kind, name)

    def installed_type(self, package: str, kind: str, name: str) -> Any:
        """A msg/srv class of the ROS install itself (the wheels, the underlay, a system ROS), never the
        workspace's: e.g. ``("tf2_msgs", "msg", "TFMessage")``, which only the source-built underlay has.

        Loaded as :meth:`interface_type` loads a workspace's (:mod:`ros2course.ros.interfaces`): the grading
        process started before the install's ``lib/`` could be on its library path, so the package's
        typesupport libraries are loaded from its prefix. Nothing of a submission is involved, so batch
        grading uses it as is.

        Raises:
            NotGradable: the package is not in the ROS install, or its types do not load.
        """
        return workspace_type(self.base_env, package, kind, name)

    def reference_package(self, package: str) -> Path:
        """The folder of the course's own reference source of ``package`` (``solutions/src/...``), read-only.

        In batch grading the copy in the trusted build is used: ``solutions/`` is hidden from the sandbox.

        Raises:
            CourseError: the lesson does not declare ``package`` in ``references:`` (lesson.yaml), or the
                course has no such reference package (both faults of the course, never the learner's).
        """
        if package not in self.lesson.references:
            raise CourseError(f"the grader of {self.lesson.id} reads the reference of {package} but its lesson.yaml "
                              "does not declare it", f"a fault of the course: add 'references: [{package}]' to lesson.yaml")
        src = (self.trusted_interfaces / "src" if self.trusted_interfaces is not None
               else self.lesson.course.solutions / "src")
        found = find_packages(src)
        if package not in found:
            raise CourseError(f"the course has no reference package {package} in {src}",
                              "a fault of the course or of the grading run: grade through ros2course grade, which "
                              "copies the lesson's references")
        return found[package][0]

    def submission_folder(self, name: str, fill: Callable[[Path], None] | None = None) -> Path:
        """A fresh folder ``log_dir/<name>`` that the programs the grader runs as the submission may write.

        ``fill(folder)`` runs first, as the grader (copy sources, templates); then, in batch grading, the
        whole tree is given to the submission's uid (:func:`ros2course.sandbox.give_tree`) and the grader
        only reads it from then on (writing into a folder the submission owns could follow a link it
        planted). Under ``check`` the learner owns everything already, so both paths see the same folders.

        Args:
            name: a folder name relative to the check's log folder (``"cmake-build"``); an earlier folder
                of that name is removed first.
            fill: called with the new, empty folder before it changes hands.

        Returns:
            the folder (absolute).
        """
        folder = self.log_dir / name
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
        if fill is not None:
            fill(folder)
        sandbox.give_tree(folder)
        return folder

    def find_executable(self, package: str, executable: str) -> tuple[Path | None, str]:
        """Resolve ``package``/``executable`` the way ``ros2 run`` does.

        The package's prefix in the workspace overlay's ament index (:func:`ros2course.ros.index.package_prefix`,
        as ``get_package_prefix``), then ``<prefix>/lib/<package>/<executable>`` (ros2run source).

        Returns:
            ``(path, observed)``: the path (None when not found) and a sentence saying what was found, for
            the check's "observed".
        """
        prefix = ament_index.package_prefix(package, self.overlay())
        if prefix is None:
            return None, f"package {package} is not in the ament index (was it built and installed?)"
        lib = prefix / "lib" / package
        candidate = lib / executable
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate, f"{candidate.relative_to(self.workspace_root) if candidate.is_relative_to(self.workspace_root) else candidate}"
        others = sorted(p.name for p in lib.iterdir() if p.is_file()) if lib.is_dir() else []
        listing = ", ".join(others) if others else "nothing"
        return None, f"no executable {executable} in {lib}; found: {listing}"

    def find_share(self, package: str) -> Path | None:
        """``install/<package>/share/<package>`` as ``ros2 launch`` finds it (ament index), or None."""
        return ament_index.package_share(package, self.overlay())

    # --- processes ---------------------------------------------------------------------------------

    def process(self, argv: Sequence[str], env: dict[str, str], label: str, *, cwd: Path | None = None,
                **options: Any) -> LearnerProcess:
        """A learner process, registered to be stopped with the grading but not started yet.

        Args:
            argv: the command (``argv[0]`` a path or a name on ``env``'s PATH).
            env: its whole environment.
            label: names its log files (``<label>.stdout.log`` in ``log_dir``).
            cwd: its working directory (default: the workspace root).
            options: :class:`~ros2course.run.process.LearnerProcess`'s own (``ros_sigint``, ``deadline`` in seconds).

        Its ``TMPDIR`` is the check's own ``log_dir/tmp`` (a :meth:`submission_folder`, made once for every
        process of the check, whichever part's thread starts one first), so what it leaves in a
        temporary folder stays with the check's logs instead of in the machine's ``/tmp``: ``ros2 launch``
        writes each node's parameters to a ``launch_params_*`` file there (launch_ros's
        ``evaluate_parameters``, ``tempfile.NamedTemporaryFile(delete=False)``) and never removes it.
        """
        with self._tmpdir_lock:  # made once: a second submission_folder() would empty it under a running process
            if self._tmpdir is None:
                self._tmpdir = self.submission_folder("tmp")
        env = {**env, "TMPDIR": str(self._tmpdir)}
        proc = LearnerProcess(list(argv), env, self.log_dir, label, cwd=cwd or self.workspace_root, **options)
        self.processes.append(proc)
        return proc

    def run_colcon(self, args: Sequence[str], *, timeout: float = 120.0) -> subprocess.CompletedProcess:
        """Run ``colcon ARGS`` in the workspace folder as the learner's terminal would, and wait for it.

        colcon runs each package's ``setup.py`` (the submission's code), so it runs as the submission
        (:mod:`ros2course.sandbox`), with the ROS install's environment (``base_env``) and no standard input.

        Args:
            args: colcon's arguments, global options first (``["--log-base", "/dev/null", "list"]``).
            timeout: seconds before colcon is killed.

        Raises:
            subprocess.TimeoutExpired: colcon ran longer than ``timeout``.
        """
        return sandbox.run([*build_mod.colcon_command(self.base_env), *args], cwd=self.workspace_root,
                           env=dict(self.base_env), capture_output=True, text=True, timeout=timeout, check=False,
                           stdin=subprocess.DEVNULL)

    def stop_processes(self) -> None:
        """Stop every process started here: Ctrl+C, then SIGTERM after 2 s, then SIGKILL after 2 s more."""
        for proc in self.processes:
            proc.stop(sigint_timeout=2.0, sigterm_timeout=2.0)
