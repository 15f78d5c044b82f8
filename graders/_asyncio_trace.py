"""Running a learner's asyncio code under a tracing wrapper, and reading the trace.

The wrapper (a lesson's probe program, e.g. ``graders/data/python_asyncio/wrapper.py``)
replaces ``random`` with known rolls per asyncio task and writes a JSON list of
events: ``["draw", task, value, seconds]``, ``["out", task, text, seconds]``
(text printed; task -1 outside any task), ``["scenario", name]``,
``["result", name, value]``, ``["error", where, "Type: message"]``,
``["function", exists, is_coroutine]``. Tasks are numbered from 0 in the order
they first draw.

Concurrency is judged on the order of events (a task draws while another one
is still retrying), never on wall-clock times: the tutorial's point (ch. 2.5)
is that ``await asyncio.sleep()`` lets other tasks run, ``time.sleep()`` does not.
Times judge only the pause itself (:meth:`Trace.pauses`), within wide bounds.
"""

from __future__ import annotations

import dataclasses
import json
import re
import sys
from pathlib import Path

from ros2course.kit import Session
from ros2course.kit.programs import ProgramRun, run_program
from ros2course.kit.python_programs import python_env

#: A result line of the examples, as the lesson words it: The result of task=<tag> was <result>.
RESULT_LINE = re.compile(r"^The result of task=(?P<tag>\S+) was (?P<value>\S+)\.$")
_NUMBER = re.compile(r"\d*\.\d+(?:[eE][-+]?\d+)?")


@dataclasses.dataclass(frozen=True)
class Trace:
    """The events of one traced run (a list of JSON arrays, see the module docstring)."""

    events: list

    def draw_order(self) -> list[int]:
        """The task index of every draw, in order."""
        return [e[1] for e in self.events if e[0] == "draw"]

    def interleaved(self) -> bool:
        """True when task 1 draws between two draws of task 0 (both were running at once)."""
        order = self.draw_order()
        if 0 not in order or 1 not in order:
            return False
        return order.index(1) < max(i for i, task in enumerate(order) if task == 0)

    def describe_order(self) -> str:
        """Draw order as text, e.g. ``1 2 1 2 1 1`` (task numbers from 1, as the learner counts)."""
        order = self.draw_order()
        return " ".join(str(task + 1) for task in order[:24]) + (" ..." if len(order) > 24 else "")

    def draw_seconds(self) -> float:
        """Seconds from the first draw to the last (0 without draws)."""
        stamps = [e[3] for e in self.events if e[0] == "draw"]
        return max(stamps) - min(stamps) if stamps else 0.0

    def pauses(self, index: int) -> list[float]:
        """Seconds between consecutive draws of task ``index`` (empty with fewer than 2 draws)."""
        stamps = [e[3] for e in self.events if e[0] == "draw" and e[1] == index]
        return [later - earlier for earlier, later in zip(stamps, stamps[1:])]

    def cancelled(self, plans: list[list[float]]) -> str:
        """``"; task 1 stopped after 3 of its 8 rolls ..."`` when a task never drew the winning (last) roll of its
        plan in ``plans`` (one list of rolls per task, in the order tasks first draw), else ""."""
        order = self.draw_order()
        for index, plan in enumerate(plans):
            drawn = order.count(index)
            if 0 < drawn < len(plan):
                return (f"; task {index + 1} stopped after {drawn} of its {len(plan)} rolls without returning: the "
                        "program ended while it was still retrying (asyncio.run cancels every task still running "
                        "when its coroutine returns), so await every task you created, not only the last one")
        return ""

    def blocking(self) -> list[list]:
        """The ``["blocking", task, seconds asked, seconds]`` events: ``time.sleep`` called inside a task."""
        return [e for e in self.events if e[0] == "blocking"]

    def idle_after_draws(self) -> float | None:
        """Seconds from the last draw to the run's end (None when either is missing): a program that sleeps
        instead of awaiting its tasks ends well after the last one returned."""
        stamps = [e[3] for e in self.events if e[0] == "draw"]
        end = next((e[1] for e in reversed(self.events) if e[0] == "end"), None)
        return end - max(stamps) if stamps and end is not None else None

    def last_draw(self, index: int) -> int:
        """Position of task ``index``'s last draw in the events (-1 if it never drew)."""
        positions = [i for i, e in enumerate(self.events) if e[0] == "draw" and e[1] == index]
        return positions[-1] if positions else -1

    def mentions(self, index: int, value: float, tolerance: float) -> list[int]:
        """Positions where text printed outside task ``index`` shows ``value`` (within ``tolerance``).

        Text a task prints itself (its own "Done." line, even with the roll) is not its result being handled.
        """
        return [position for position, e in enumerate(self.events) if e[0] == "out" and e[1] != index
                and any(abs(float(number) - value) <= tolerance for number in _NUMBER.findall(e[2]))]

    def error(self, run: ProgramRun) -> str:
        """What went wrong, in one sentence: the last recorded exception, else how the run ended."""
        errors = [e[2] for e in self.events if e[0] == "error"]
        return errors[-1] if errors else run.describe()

    def first(self, kind: str) -> list | None:
        """The first event of ``kind`` (e.g. ``"function"``), None if there is none."""
        return next((e for e in self.events if e[0] == kind), None)

    def scenario(self, name: str) -> tuple[list | None, Trace]:
        """``(outcome, events)`` of probe scenario ``name``: its ``result`` or ``error`` event (None if it never
        ended) and its own events."""
        start = next((i for i, e in enumerate(self.events) if e[0] == "scenario" and e[1] == name), None)
        if start is None:
            return None, Trace([])
        end = next((i for i, e in enumerate(self.events) if i > start and e[0] == "scenario"), len(self.events))
        part = self.events[start + 1:end]
        return next((e for e in part if e[0] in ("result", "error")), None), Trace(part)


def run_traced(s: Session, wrapper: Path, mode: str, target: str, plans: list[list[float]], label: str, *,
               cwd: Path, timeout: float = 20.0) -> tuple[ProgramRun, Trace]:
    """Run ``python <wrapper> <trace> <mode> <target> <plans>`` in ``cwd``; return the run and its trace.

    The trace file is written into ``<log_dir>/<label>.trace/`` (a :meth:`Session.submission_folder`:
    the program runs as the submission; never the learner's folder); a run that wrote none (it crashed
    before) comes back with an empty trace.
    """
    trace = s.submission_folder(f"{label}.trace") / "trace.json"
    run = run_program(s, [sys.executable, str(wrapper), str(trace), mode, target, json.dumps(plans)], label,
                      timeout=timeout, env=python_env(s), cwd=cwd)
    try:
        events = json.loads(trace.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        events = []
    return run, Trace(events if isinstance(events, list) else [])


def result_lines(s: Session, trace: Trace, check_id: str, wanted: list[tuple[str, float]], tolerance: float) -> None:
    """``check_id`` (python-asyncio's ``await_result_lines``, ``callback_result_lines``): a line 'The result of
    task=<tag> was <result>.' for each (tag, result) of ``wanted``, the result within ``tolerance``, each with its
    own task's result (the tag is the one the example gave the task
    that drew it: a callback bound to the wrong tag prints task 1's result as task2's)."""
    text = "".join(str(e[2]) for e in trace.events if e[0] == "out")
    found = {}
    for line in text.splitlines():
        match = RESULT_LINE.match(line.strip())
        if match:
            try:
                found.setdefault(match.group("tag"), []).append(float(match.group("value")))
            except ValueError:
                continue
    missing = [f"task={tag} ({value})" for tag, value in wanted
               if not any(abs(v - value) <= tolerance for v in found.get(tag, []))]
    printed = [line.strip() for line in text.splitlines() if line.strip()]
    others = [line for line in printed if not RESULT_LINE.match(line) and "retry" not in line.lower()
              and not line.endswith("Done.")]
    s.record(check_id, not missing,
             "both result lines were printed" if not missing else
             f"no result line for {' and '.join(missing)}" + (
                 f"; result lines printed: {', '.join(f'task={tag} was {v}' for tag, vs in found.items() for v in vs)}"
                 if found else "")
             + (f"; other lines: {'; '.join(repr(o) for o in others[:3])}" if others else ""),
             "; ".join(f"'The result of task={tag} was {value}.'" for tag, value in wanted))


def progress_lines(s: Session, part: Trace) -> None:
    """Record ``prints_progress`` on the probe's default scenario (tag "probe", 3 misses then a hit): the lines
    the python-asyncio contract names."""
    printed = [e[2].strip() for e in part.events if e[0] == "out"]
    retries = [line for line in printed if "probe" in line and "retry" in line.lower()]
    done = [line for line in printed if "probe Done." in line]
    shown = "; ".join(printed[:5]) + (" ..." if len(printed) > 5 else "") if printed else "nothing"
    s.record("prints_progress", len(retries) == 3 and len(done) == 1,
             f"with 3 misses then a hit it printed {len(retries)} retry line(s) and {len(done)} 'probe Done.' "
             f"line(s): {shown}",
             "3 lines saying a retry is needed (with the tag), then 'probe Done.' (the tag was 'probe')")
