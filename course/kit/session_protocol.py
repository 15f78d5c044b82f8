"""The grader's door to the engine: :class:`Session`, what a grader and a kit step may use of the session
they are handed (issue 38).

The engine's :class:`~ros2course.grade.session.GradingSession` is much more (timings, recordings,
diagnosis, closers, the sandbox); a grader sees this much, and ``tests/test_session_protocol.py``
keeps it so: every member used on ``s`` in ``graders/`` and ``ros2course.kit`` is one of these, and
``GradingSession`` provides each with this signature. Grouped as the issue asks:

* the verdict book: :meth:`record`, :meth:`amend`, :meth:`require`, :meth:`unmet_need`, :attr:`results`,
  :meth:`part`, :meth:`phase`, :meth:`on_close`, :meth:`add_plot`;
* the observer: :attr:`ros`, :attr:`graph`, :meth:`new_graph`, :attr:`random`;
* the machine: :meth:`launch`, :meth:`start_program`, :meth:`run_colcon`, :meth:`overlay`,
  :attr:`base_env`, :meth:`find_executable`, :meth:`find_share`, :meth:`interface_type`,
  :meth:`installed_type`, :meth:`reference_package`, :meth:`submission_folder`,
  :attr:`workspace_root`, :attr:`log_dir`, :attr:`lesson`.

Annotate a grader's ``grade(s: Session)`` with it; the engine passes its ``GradingSession``.
"""

from __future__ import annotations

import random
import subprocess
from collections.abc import Callable, Mapping, Sequence
from contextlib import AbstractContextManager
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from ros2course.grade.results import CheckResult
from ros2course.run.process import LearnerProcess


@runtime_checkable
class Session(Protocol):
    """What a grader may use of its grading session (the engine's ``GradingSession`` implements it).

    Attributes:
        lesson: the :class:`~ros2course.lesson.catalog.Lesson` being graded (its id, packages, folder).
        workspace_root: the learner's workspace folder (``src/``, ``build/``, ``install/`` inside), absolute.
        log_dir: the check's log folder (learner process logs, recordings), absolute; the grader may write here.
        base_env: the ROS install's environment (no workspace overlay, no domain id), ``{name: value}``.
        results: verdicts so far, ``{check id: CheckResult}`` (read it; write through :meth:`record`).
    """

    lesson: Any
    workspace_root: Path
    log_dir: Path
    base_env: dict[str, str]
    results: dict[str, CheckResult]

    # --- the verdict book --------------------------------------------------------------------------

    def record(self, check_id: str, passed: bool, observed: str, expected: str, hint: str | None = None,
               fraction: float | None = None, window: tuple[float, float] | None = None,
               band: tuple[float, float] | None = None, band_of: str = "mean") -> bool:
        """Record the verdict on ``check_id`` (declared in ``CHECKS``) and return ``passed``.

        ``observed``/``expected`` in the learner's terms; ``hint`` replaces the check's hint; ``fraction``
        in [0, 1] gives partial credit; ``window`` the judged span (``time.time()`` seconds, first and
        last); ``band`` the allowed interval between events (seconds, ``(low, high)``) of the statistic
        ``band_of`` (``"mean"`` or ``"median"``). A check whose needs failed is recorded "not checked".

        Raises:
            KeyError: ``check_id`` is not declared.
        """
        ...

    def amend(self, check_id: str, *, observed: str | None = None, hint: str | None = None) -> None:
        """Replace a recorded verdict's observed text or hint; points and pass/fail stay.

        Raises:
            KeyError: ``check_id`` has no verdict yet.
        """
        ...

    def require(self, *check_ids: str) -> None:
        """Go on only if every check in ``check_ids`` passed.

        Raises:
            Unmet: one did not (the engine marks the checks that need it "not checked").
        """
        ...

    def unmet_need(self, check_id: str) -> str | None:
        """Why ``check_id`` cannot be judged (its first need that did not pass), or None."""
        ...

    def wanted(self, check_id: str) -> bool:
        """Whether ``check_id``'s verdict can still matter. Always True when a learner or a class is graded;
        False only under ``dev validate --until-settled`` for a check none of the case's named checks needs
        (it is left "not checked"): a grader may then skip work only that check's verdict uses, e.g. one
        mutant's test run (kit 2.7)."""
        ...

    def part(self, name: str = "", *, own_graph: bool = False) -> AbstractContextManager[None]:
        """A ``with`` block grading one independent part (its checks declare ``part=name``); an
        :class:`Unmet` inside ends the part only. ``own_graph``: the part's nodes run in a private
        ROS graph of their own (:attr:`graph` inside the block)."""
        ...

    def phase(self, name: str) -> AbstractContextManager[None]:
        """A ``with`` block whose wall time is added to the timing ``name`` (``start``, ``observe``,
        ``stop``...; seconds, shown by ``check --timings``)."""
        ...

    def on_close(self, action: Callable[[], Any]) -> None:
        """Run ``action()`` when the current part (or ``grade()``) ends, even after :class:`Unmet`;
        newest first (a Ctrl+C check registered after a probe runs before the probe closes)."""
        ...

    def add_plot(self, title: str, times: Sequence[float], series: Mapping[str, Sequence[float]],
                 unit: str = "") -> None:
        """Attach time series to the result (``times`` in seconds, one list per series name, in ``unit``);
        shown by ``check`` and ``evidence``; never changes a verdict."""
        ...

    # --- the observer -------------------------------------------------------------------------------

    @property
    def ros(self) -> Any:
        """The check's private ROS graph (a :class:`~ros2course.run.probes.RosSession`: its own domain id,
        the grader's node, probes), opened on first use."""
        ...

    @property
    def graph(self) -> Any:
        """The graph the calling thread's steps observe: the innermost open part's own graph, else :attr:`ros`."""
        ...

    def new_graph(self) -> Any:
        """Another private ROS graph (its own domain id), closed with the check."""
        ...

    @property
    def random(self) -> random.Random:
        """Random draws for this submission (seeded by its content: the same files, the same draws)."""
        ...

    # --- the machine --------------------------------------------------------------------------------

    def launch(self, path: Path, name: str, args: list[str] | None = None, graph: Any = None) -> LearnerProcess:
        """Start a learner executable as the submission, in ``graph`` (default :attr:`graph`), with the
        sourced workspace; ``name`` labels its logs. Stopped at the end of the check."""
        ...

    def start_program(self, argv: list[str], label: str, *, env: dict[str, str] | None = None,
                      cwd: Path | None = None, deadline: float = 60.0, stdin_open: bool = False) -> LearnerProcess:
        """Start a learner program that is not a ROS node (a script, a binary, pip) as the submission;
        killed ``deadline`` seconds after start; ``env`` default :attr:`base_env`, ``cwd`` the workspace;
        ``stdin_open``: stdin a pipe nobody writes to (a question waits), else ``/dev/null``."""
        ...

    def run_colcon(self, args: Sequence[str], *, timeout: float = 120.0) -> subprocess.CompletedProcess:
        """Run ``colcon ARGS`` in the workspace as the learner's terminal would; wait up to ``timeout`` s."""
        ...

    def overlay(self) -> dict[str, str]:
        """The sourced workspace's environment (``install/setup.bash`` over :attr:`base_env`), no domain id."""
        ...

    def find_executable(self, package: str, executable: str) -> tuple[Path | None, str]:
        """``(path, observed)``: ``package``'s ``executable`` as ``ros2 run`` finds it (ament index, then
        ``lib/<package>/``), or ``(None, why not)``."""
        ...

    def find_share(self, package: str) -> Path | None:
        """``install/<package>/share/<package>`` as ``ros2 launch`` finds it, or None."""
        ...

    def interface_type(self, package: str, kind: str, name: str) -> Any:
        """A message/service/action class (``kind`` ``msg``, ``srv`` or ``action``) generated in the
        learner's workspace.

        Raises:
            Unmet: the workspace does not provide it.
        """
        ...

    def installed_type(self, package: str, kind: str, name: str) -> Any:
        """A message/service/action class of the ROS install itself (never the learner's workspace)."""
        ...

    def reference_package(self, package: str) -> Path:
        """The course's own reference source folder of ``package`` (read-only)."""
        ...

    def submission_folder(self, name: str, fill: Callable[[Path], None] | None = None) -> Path:
        """A fresh folder ``log_dir/<name>`` the submission's programs may write (``fill(path)`` puts the
        grader's files in first, e.g. a stand-in library)."""
        ...


#: Every member of :class:`Session`, sorted.
MEMBERS: tuple[str, ...] = tuple(sorted(
    {name for name in Session.__dict__ if not name.startswith("_")} | set(Session.__annotations__)))

__all__ = ["MEMBERS", "Session"]
