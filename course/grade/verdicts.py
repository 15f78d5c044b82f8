"""The verdict book of one grading: :class:`VerdictBook`, the part of a grading session that holds verdicts.

It keeps each check's verdict (:class:`~ros2course.grade.results.CheckResult`), follows the
checks' ``needs`` (a check whose need failed is "not checked"), stops a part whose needs are
unmet (:class:`~ros2course.grade.checklist.Unmet`), keeps each verdict's judged window and
allowed band, the closing actions of the open parts, and ends a ``dev validate --until-settled``
grading once its verdict is settled. It needs no ROS, no process and no file: built and tested
on its own (``tests/test_verdict_book.py``). :class:`~ros2course.grade.session.GradingSession`
composes it with the observer (graphs, recording, diagnosis) and the machine view
(:mod:`ros2course.grade.machine`); a grader reaches it through the session's
:class:`~ros2course.kit.Session` members (``record``, ``amend``, ``require``, ``unmet_need``,
``part``, ``on_close``, ``results``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from ros2course.grade.checklist import Check, StopWhen, Unmet, VerdictSettled, check_dependencies
from ros2course.grade.results import NOT_CHECKED, CheckResult


@dataclasses.dataclass(frozen=True)
class Band:
    """The interval between events a verdict allowed, kept with its check's recording window.

    Attributes:
        low, high: seconds (a rate's period minus and plus its tolerance, kit.rate).
        of: the statistic of the intervals the band bounded: ``"mean"`` or ``"median"``.
    """

    low: float
    high: float
    of: str = "mean"

    def metadata(self) -> dict[str, Any]:
        """The band's fields in the recording's check metadata (``ros2course evidence --plot`` reads them)."""
        return {"band": [self.low, self.high], "band_of": self.of}


#: What the book asks of its owner when a verdict is written: ``(check, passed) -> diagnosis``, a list of
#: :class:`~ros2course.run.diagnose.Diagnosis` for a failed check ([] for a passed one, or none to give).
#: Called for every verdict, passed or not (the observer keeps the graph at a part's first verdict).
OnVerdict = Callable[[Check, bool], list[Any]]


class VerdictBook:
    """The verdicts of one grading of one lesson, in the order its grader declares its checks.

    Args:
        checks: the grader's ``CHECKS``, in declaration order.
        stop_when: ``dev validate --until-settled`` only: stop at the grader's next step once the
            verdicts settle the case (:meth:`stop_if_settled`); None for every real grading.

    Attributes:
        checks: ``{check id: Check}``.
        order: the check ids in declaration order.
        results: ``{check id: CheckResult}`` recorded so far.
        windows: ``{check id: (start_ns, end_ns)}``, the wall-clock window each verdict judged.
        bands: ``{check id: Band}``, the interval between events a verdict allowed.

    Raises:
        CourseError: a check needs an unknown or later check (:func:`~ros2course.grade.checklist.check_dependencies`).

    Thread-safe for the lesson graders' use: two halves of a lesson graded on two threads at once
    (``kit.parts.at_once``) each record into their own part; the window of a verdict starts at the
    previous verdict, or the part's start, of the same thread.
    """

    def __init__(self, checks: Sequence[Check], stop_when: StopWhen | None = None) -> None:
        check_dependencies(list(checks))
        self.checks = {c.id: c for c in checks}
        self.order = [c.id for c in checks]
        self.results: dict[str, CheckResult] = {}
        self.windows: dict[str, tuple[int, int]] = {}
        self.bands: dict[str, Band] = {}
        self._stop_when = stop_when
        self._grading_thread = threading.current_thread()
        self._started_ns = time.time_ns()
        # per thread: the stack of open parts' closing actions (innermost last) and the start of the next window
        self._local = threading.local()

    # --- settling (dev validate --until-settled) ---------------------------------------------------

    def stop_if_settled(self) -> None:
        """Raise :class:`~ros2course.grade.checklist.VerdictSettled` when the verdicts recorded so far settle
        ``stop_when``, on the thread that made the book (the one that runs ``grade()``; a worker thread's half
        runs on until it ends).

        Called as the grader takes its next step (records another check, requires one, opens a part,
        reaches for a graph, starts a process), never by :meth:`amend`: a verdict's own amendment, made
        right after it, is kept. Raises once: it disarms itself.
        """
        if not self._stop_when or threading.current_thread() is not self._grading_thread:
            return
        for check_id in self._stop_when.judged:
            # a named check whose need failed can only be written "not checked" (record() would): its verdict
            # is settled now, not when the grading reaches it
            if check_id not in self.results and check_id in self.checks:
                blocker = self.unmet_need(check_id)
                if blocker is not None:
                    self.not_checked(check_id, blocker)
        if self._stop_when.reached(self.results):
            self._stop_when = None
            raise VerdictSettled

    def wanted(self, check_id: str) -> bool:
        """Whether ``check_id``'s verdict can still matter: False only while a ``dev validate --until-settled``
        case waits for its named checks (:attr:`~ros2course.grade.checklist.StopWhen.judged`) and none of
        them needs ``check_id``, directly or through other needs. Such a check is left "not checked" when the
        case settles, so a grader may skip work that only its verdict uses (a learner's and a class's gradings
        want every check).
        """
        judged = self._stop_when.judged if self._stop_when else frozenset()
        if not judged:
            return True
        seen: set[str] = set()
        todo = [c for c in judged if c in self.checks]
        while todo:
            current = todo.pop()
            if current not in seen:
                seen.add(current)
                todo += [need for need in self.checks[current].needs if need in self.checks]
        return check_id in seen

    # --- verdicts ----------------------------------------------------------------------------------

    def record(self, check_id: str, passed: bool, observed: str, expected: str, hint: str | None = None,
               fraction: float | None = None, window: tuple[float, float] | None = None,
               band: tuple[float, float] | None = None, band_of: str = "mean",
               on_verdict: OnVerdict | None = None) -> bool:
        """Write the verdict on ``check_id``; returns ``passed`` (False when it was not checked).

        A check one of whose needs did not pass is written "not checked" instead; a check the engine
        already marked "not checked" (its part stopped) keeps that verdict.

        Args:
            observed: what the grader saw, in the learner's terms.
            expected: what the lesson's contract asks for.
            hint: overrides the check's default hint (kept only on failure).
            fraction: partial credit in [0, 1] (default: all or nothing).
            window: the wall-clock span the verdict judged (``time.time()`` seconds: first and last);
                default: from this thread's previous verdict (or the start of its part) to now.
            band: the interval between events the verdict allowed, ``(low, high)`` seconds.
            band_of: the statistic of the intervals the band was applied to: ``"mean"`` or ``"median"``.
            on_verdict: called as ``on_verdict(check, passed)`` before the verdict is written; what it
                returns is the failed verdict's diagnosis.

        Raises:
            KeyError: ``check_id`` is not declared.
            VerdictSettled: an earlier verdict settled a ``dev validate --until-settled`` case.
        """
        self.stop_if_settled()
        check = self.checks[check_id]
        blocker = self.unmet_need(check_id)
        if blocker is not None:
            self.not_checked(check_id, blocker)
            return False
        previous = self.results.get(check_id)
        if previous is not None and previous.skipped:
            return False
        share = (1.0 if passed else 0.0) if fraction is None else max(0.0, min(1.0, fraction))
        now = time.time_ns()
        start = getattr(self._local, "mark", self._started_ns)
        self._local.mark = now
        self.windows[check_id] = (int(window[0] * 1e9), int(window[1] * 1e9)) if window else (start, now)
        if band is not None:
            self.bands[check_id] = Band(float(band[0]), float(band[1]), band_of)
        diagnosis = on_verdict(check, passed) if on_verdict is not None else []
        self.results[check_id] = CheckResult(check.id, check.name, round(check.points * share, 3), check.points,
                                             passed, observed, expected,
                                             "" if passed else (hint if hint is not None else check.hint),
                                             diagnosis=[] if passed else diagnosis, visibility=check.visibility)
        return passed

    def amend(self, check_id: str, *, observed: str | None = None, hint: str | None = None) -> None:
        """Replace a recorded verdict's observed text or hint; its points and pass/fail stay.

        Raises:
            KeyError: ``check_id`` has no verdict yet.
        """
        result = self.results[check_id]
        self.results[check_id] = dataclasses.replace(
            result, observed=result.observed if observed is None else observed,
            hint=result.hint if hint is None else hint)

    def unmet_need(self, check_id: str) -> str | None:
        """Why ``check_id`` cannot be judged: a sentence naming the first of its needs that did not pass.

        None while every need passed or is still to be judged. Needs are followed through: a need
        that was itself not checked blocks too.
        """
        for need in self.checks[check_id].needs:
            result = self.results.get(need)
            if result is not None and not result.passed:
                return (f"'{self.checks[need].name}' was not checked" if result.skipped
                        else f"'{self.checks[need].name}' failed")
            if result is None and (blocked := self.unmet_need(need)) is not None:
                return blocked
        return None

    def not_checked(self, check_id: str, reason: str) -> None:
        """Write ``check_id`` "not checked" because of ``reason`` (no points; the check's hint kept)."""
        check = self.checks[check_id]
        self.results[check_id] = CheckResult(check.id, check.name, 0.0, check.points, False,
                                             f"{NOT_CHECKED}{reason}", "(depends on the failed check above)",
                                             check.hint, skipped=True, visibility=check.visibility)

    def require(self, *check_ids: str) -> None:
        """Go on only if every check in ``check_ids`` passed.

        Raises:
            Unmet: one of them failed or is not recorded (the current part ends).
            VerdictSettled: as :meth:`record`.
        """
        self.stop_if_settled()
        for check_id in check_ids:
            result = self.results.get(check_id)
            if result is None or not result.passed:
                raise Unmet(self.unmet_need(check_id) or f"'{self.checks[check_id].name}' did not pass")

    def stop_part(self, name: str, reason: str) -> None:
        """Write every unrecorded check of part ``name`` ("" = every part) "not checked" because of ``reason``.

        A check whose own needs failed gets that reason instead.

        Raises:
            VerdictSettled: as :meth:`record` (after writing them).
        """
        for check_id in self.order:
            if check_id not in self.results and (not name or self.checks[check_id].part == name):
                self.not_checked(check_id, self.unmet_need(check_id) or reason)
        self.stop_if_settled()

    def leave_unjudged(self, reason: str) -> None:
        """Write every check not recorded yet "not checked" because of ``reason``, whatever its needs: the
        end of a grading stopped early (``dev validate --until-settled``), where no check after the stop was judged.
        """
        for check_id in self.order:
            if check_id not in self.results:
                self.not_checked(check_id, reason)

    def ordered(self, recording: str | None = None) -> list[CheckResult]:
        """Every declared check's result, in declaration order; unrecorded ones become "not checked".

        Args:
            recording: the path of the grading's recording, or None: each failed verdict (not a
                "not checked" one) then carries its ``evidence`` (the recording and the window it judged).
        """
        for check_id in self.order:
            if check_id not in self.results:
                self.not_checked(check_id, self.unmet_need(check_id) or "the grader stopped before this check")
        out = []
        for check_id in self.order:
            result = self.results[check_id]
            if recording is not None and not result.passed and not result.skipped and check_id in self.windows:
                start, end = self.windows[check_id]
                result = dataclasses.replace(result, evidence={"recording": recording,
                                                               "start_ns": start, "end_ns": end})
            out.append(result)
        return out

    # --- parts -------------------------------------------------------------------------------------

    @contextlib.contextmanager
    def part(self, name: str = "") -> Iterator[None]:
        """A ``with`` block grading part ``name`` of the lesson, with its own closing actions.

        :class:`~ros2course.grade.checklist.Unmet` raised inside ends only this part: its closing
        actions run (newest first), then its unrecorded checks are written "not checked" with the
        reason. Any other end (VerdictSettled, a grader's crash, KeyboardInterrupt) runs every closing
        action, however another fails, and goes on. The window of the part's first verdict starts here.

        Raises:
            VerdictSettled: as :meth:`record`, on entry.
        """
        self.stop_if_settled()
        self._closers.append([])
        self._local.mark = time.time_ns()
        try:
            yield
        except Unmet as stop:
            self._run_closers(self._closers.pop())
            self.stop_part(name, str(stop))
        except BaseException:
            # a world, a stand-in server or a probe still spinning on the part's graph when the session
            # shuts that graph down crashed the grading process (SIGSEGV, seen twice in CI under
            # dev validate --until-settled): every closing action runs, whatever another raised
            self._run_closers(self._closers.pop(), keep_going=True)
            raise
        else:
            self._run_closers(self._closers.pop())

    def on_close(self, action: Callable[[], Any]) -> None:
        """Run ``action()`` when the current part (or ``grade()``) ends, even after ``Unmet``.

        Raises:
            IndexError: no part is open on the calling thread (the engine runs ``grade()`` inside one).
        """
        self._closers[-1].append(action)

    @staticmethod
    def _run_closers(closers: list[Callable[[], Any]], keep_going: bool = False) -> None:
        """Run ``closers`` newest first; ``Unmet`` from one never stops the others (nor, with
        ``keep_going``, any ``Exception``: the part is already ending with an error of its own)."""
        for action in reversed(closers):
            with contextlib.suppress(Exception if keep_going else Unmet):
                action()

    @property
    def _closers(self) -> list[list[Callable[[], Any]]]:
        """The calling thread's stack of open parts' closing actions."""
        if not hasattr(self._local, "closers"):
            self._local.closers = []
        return self._local.closers
