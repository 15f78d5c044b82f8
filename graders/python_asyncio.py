"""Grader for ``python-asyncio`` (seed ch. 2.5): a coroutine and two ways to use its results.

Everything runs the learner's code for real, through :mod:`graders.kit.programs`,
with ``python/minimalist_package`` as the working directory (as ``python -m``
is used in the tutorial). A small wrapper script, written under ``s.log_dir``,
replaces ``random.random`` / ``random.uniform`` with a known sequence of rolls
*per asyncio task* (so the verdict does not depend on luck or on scheduling)
and records, in order, every roll drawn and every piece of text printed, with
the task that printed it. The checks read that trace:

* concurrency is judged on the order of the draws (the second task draws
  while the first one is still retrying), never on wall-clock times;
* "await order" and "as it completes" are judged on where each result is
  printed relative to the other task's final draw.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

from graders.kit import Check, GradingSession, Unmet
from graders.kit.programs import ProgramRun, run_program

#: No continuous observation: each run ends by itself (about 1 s of asyncio.sleep at 0.1 s per retry).
WINDOW = 3.0

FOLDER = Path("python") / "minimalist_package"

#: Rolls each task draws, by the order in which tasks first draw (further tasks reuse the last plan).
#: The first task retries 7 times, the second only twice, so the second one finishes first.
EXAMPLE_PLANS = [[0.52, 0.81, 0.67, 0.93, 0.58, 0.74, 0.85, 0.0312], [0.61, 0.77, 0.0687]]
#: The successful roll of each plan above: what each task must return.
EXAMPLE_RESULTS = [plan[-1] for plan in EXAMPLE_PLANS]
#: How close a printed number must be to a result to count as printing it (allows rounding to 2 decimals).
RESULT_TOLERANCE = 0.005
#: Seconds each run may take before it is stopped (the reference needs about 1 s).
RUN_TIMEOUT = 20.0

CHECKS = [
    Check("module", "minimalist_package.minimalist_async.unlikely_to_return is an async function", 1,
          "make python/minimalist_package/minimalist_package/minimalist_async.py with "
          "'async def unlikely_to_return(tag: str, likelihood: float = 0.1) -> float:'"),
    Check("returns_roll", "unlikely_to_return retries until a roll is below 0.1, and returns that roll", 2,
          "loop: draw random.uniform(0.0, 1.0); if it is below likelihood, return it; otherwise sleep and draw again",
          needs=("module",)),
    Check("likelihood_param", "unlikely_to_return compares with its likelihood argument", 1,
          "compare the roll with the likelihood parameter, not with a fixed 0.1", needs=("module",)),
    Check("yields_between_draws", "Between draws it awaits asyncio.sleep, so two calls run concurrently", 2,
          "use 'await asyncio.sleep(0.1)', not time.sleep(0.1): time.sleep blocks every other task",
          needs=("module",)),
    Check("await_runs", "python -m ...async_await_example runs two tasks and exits 0", 1,
          "run it yourself from python/minimalist_package: python -m minimalist_package.async_await_example",
          needs=("module",)),
    Check("await_concurrent", "async_await_example runs its two tasks concurrently", 2,
          "create both tasks with asyncio.create_task() before awaiting the first one", needs=("await_runs",)),
    Check("await_order", "async_await_example prints the results in await order", 2,
          "await the tasks in the order you created them and print each result right after its await",
          needs=("await_runs",)),
    Check("callback_runs", "python -m ...async_callback_example runs two tasks and exits 0", 1,
          "run it yourself from python/minimalist_package: python -m minimalist_package.async_callback_example",
          needs=("module",)),
    Check("callback_concurrent", "async_callback_example runs its two tasks concurrently", 1,
          "create both tasks (and add their callbacks) before awaiting the first one", needs=("callback_runs",)),
    Check("callback_as_completed", "async_callback_example prints each result as soon as its task ends", 2,
          "task.add_done_callback(partial(handle_return_callback, tag)) and print the result in the callback",
          needs=("callback_runs",)),
]

#: The wrapper run instead of ``python -m``: argv = trace file, mode ("probe" or "module"), module name, plans JSON.
WRAPPER = r'''
import asyncio, inspect, io, json, os, random, runpy, sys, time, traceback

TRACE, MODE, TARGET, PLANS = sys.argv[1], sys.argv[2], sys.argv[3], json.loads(sys.argv[4])
EXTRA_DRAWS = 30  # draws allowed after a plan ends (each then rolls 0.99) before giving up
sys.argv = [TARGET]
sys.path[0] = os.getcwd()  # what 'python -m' does
events = []
state = {"plans": PLANS, "tasks": {}, "counts": {}}
start = time.monotonic()


def _task():
    try:
        return asyncio.current_task()
    except RuntimeError:
        return None


def _index(create):
    task = _task()
    tasks = state["tasks"]
    if task not in tasks:
        if not create:
            return -1
        tasks[task] = len(tasks)
    return tasks[task]


def _draw():
    index = _index(True)
    count = state["counts"].get(index, 0)
    state["counts"][index] = count + 1
    plan = state["plans"][min(index, len(state["plans"]) - 1)]
    if count >= len(plan) + EXTRA_DRAWS:
        raise RuntimeError("the grader's rolls ran out: it never accepted a roll below its likelihood")
    value = plan[count] if count < len(plan) else 0.99
    events.append(["draw", index, value, time.monotonic() - start])
    return value


def _uniform(a, b):
    return a + (b - a) * _draw()


random.random = _draw
random.uniform = _uniform


class _Tee(io.TextIOBase):
    def __init__(self, real):
        self.real = real

    def write(self, text):
        events.append(["out", _index(False), str(text), time.monotonic() - start])
        return self.real.write(text)

    def flush(self):
        self.real.flush()


sys.stdout = _Tee(sys.stdout)


def _dump():
    with open(TRACE, "w", encoding="utf-8") as handle:
        json.dump(events, handle)


def _probe():
    import importlib
    module = importlib.import_module("minimalist_package.minimalist_async")
    function = getattr(module, "unlikely_to_return", None)
    events.append(["function", function is not None, inspect.iscoroutinefunction(function)])
    if not inspect.iscoroutinefunction(function):
        return
    scenarios = [
        ("default", [[0.5, 0.95, 0.3, 0.0777]], lambda: function("probe")),
        ("likelihood", [[0.5, 0.35]], lambda: function("probe", likelihood=0.4)),
        ("gather", [[0.52, 0.81, 0.67, 0.93, 0.0312], [0.61, 0.0687]],
         lambda: asyncio.gather(function("first"), function("second"))),
    ]
    for name, plans, make in scenarios:
        state.update(plans=plans, tasks={}, counts={})
        events.append(["scenario", name])

        async def run():
            return await asyncio.wait_for(make(), 10.0)
        try:
            result = asyncio.run(run())
            events.append(["result", name, result if isinstance(result, (int, float, list)) else repr(result)])
        except BaseException as exc:  # the learner's code failed: say how
            events.append(["error", name, f"{type(exc).__name__}: {exc}"])


try:
    if MODE == "probe":
        _probe()
    else:
        runpy.run_module(TARGET, run_name="__main__", alter_sys=True)
except BaseException as exc:
    if not (isinstance(exc, SystemExit) and exc.code in (0, None)):
        events.append(["error", MODE, f"{type(exc).__name__}: {exc}"])
    raise
finally:
    _dump()
'''


def _wrapper(s: GradingSession) -> Path:
    """Write the wrapper script into ``s.log_dir`` (never into the learner's workspace) and return its path."""
    path = s.log_dir / "asyncio_wrapper.py"
    path.write_text(WRAPPER, encoding="utf-8")
    return path


def _run(s: GradingSession, mode: str, target: str, plans: list[list[float]], label: str) -> tuple[ProgramRun, list]:
    """Run the wrapper in ``mode`` on ``target``; return the run and its trace events ([] if none was written)."""
    folder = s.workspace_root / FOLDER
    trace = s.log_dir / f"{label}.trace.json"
    trace.unlink(missing_ok=True)
    env = dict(s.base_env, PYTHONUNBUFFERED="1", PYTHONDONTWRITEBYTECODE="1")
    env.pop("PYTHONPATH", None)
    run = run_program(s, [sys.executable, str(_wrapper(s)), str(trace), mode, target, json.dumps(plans)], label,
                      timeout=RUN_TIMEOUT, env=env, cwd=folder)
    try:
        events = json.loads(trace.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        events = []
    return run, events


def _error(run: ProgramRun, events: list) -> str:
    """What went wrong in a run, in one sentence (the traceback's last line or the recorded exception)."""
    errors = [e[2] for e in events if e[0] == "error"]
    return errors[-1] if errors else run.describe()


def _draw_order(events: list) -> list[int]:
    """The task index of every draw, in order."""
    return [e[1] for e in events if e[0] == "draw"]


def interleaved(order: list[int]) -> bool:
    """True when task 1 draws between two draws of task 0 (both were running at once)."""
    if 0 not in order or 1 not in order:
        return False
    last_first = max(i for i, task in enumerate(order) if task == 0)
    first_second = order.index(1)
    return first_second < last_first


def _describe_order(order: list[int]) -> str:
    """Draw order as text, e.g. ``1 2 1 2 1 1`` (task numbers from 1)."""
    return " ".join(str(task + 1) for task in order[:24]) + (" ..." if len(order) > 24 else "")


_NUMBER = re.compile(r"\d*\.\d+(?:[eE][-+]?\d+)?")


def result_mentions(events: list, index: int) -> list[int]:
    """Positions in ``events`` where text printed outside task ``index`` shows its result (within tolerance).

    Text a task prints itself (its own "Done." line, even with the roll) is not its result being handled.
    """
    target = EXAMPLE_RESULTS[min(index, len(EXAMPLE_RESULTS) - 1)]
    found = []
    for position, event in enumerate(events):
        if event[0] != "out" or event[1] == index:
            continue
        for number in _NUMBER.findall(event[2]):
            try:
                if abs(float(number) - target) <= RESULT_TOLERANCE:
                    found.append(position)
                    break
            except ValueError:
                continue
    return found


def _last_draw(events: list, index: int) -> int:
    """Position of task ``index``'s last draw in ``events`` (-1 if it never drew)."""
    positions = [i for i, e in enumerate(events) if e[0] == "draw" and e[1] == index]
    return positions[-1] if positions else -1


def _example_module(s: GradingSession, name: str) -> str | None:
    """The module name of example ``name``: flat in the package (this course) or in the tutorial's subpackage."""
    package = s.workspace_root / FOLDER / "minimalist_package"
    if (package / f"{name}.py").is_file():
        return f"minimalist_package.{name}"
    if (package / "minimalist_async" / f"{name}.py").is_file():
        return f"minimalist_package.minimalist_async.{name}"
    return None


def _probe(s: GradingSession) -> None:
    """Import the coroutine and call it directly with known rolls: module, returns_roll, likelihood_param, yields."""
    folder = s.workspace_root / FOLDER
    if not (folder / "minimalist_package").is_dir():
        s.record("module", False, f"there is no folder {FOLDER / 'minimalist_package'} in the workspace",
                 "the package folder from the previous lesson")
        raise Unmet("no minimalist_package folder")
    run, events = _run(s, "probe", "minimalist_package.minimalist_async", [[0.5]], "asyncio_probe")
    found = [e for e in events if e[0] == "function"]
    if not found:
        s.record("module", False, f"'import minimalist_package.minimalist_async' failed: {_error(run, events)}",
                 "the module imports from python/minimalist_package")
        raise Unmet("minimalist_async does not import")
    _, exists, is_coroutine = found[0]
    s.record("module", bool(exists and is_coroutine),
             "unlikely_to_return " + ("is an async def" if is_coroutine else
                                      "is a plain function (def), not a coroutine" if exists else "does not exist"),
             "'async def unlikely_to_return(tag, likelihood=0.1)' in minimalist_async")
    if not is_coroutine:
        raise Unmet("unlikely_to_return is not a coroutine")

    def scenario(name: str) -> tuple[object, list]:
        start = next((i for i, e in enumerate(events) if e[0] == "scenario" and e[1] == name), None)
        if start is None:
            return None, []
        end = next((i for i, e in enumerate(events) if i > start and e[0] == "scenario"), len(events))
        part = events[start + 1:end]
        outcome = next((e for e in part if e[0] in ("result", "error")), None)
        return outcome, part

    outcome, part = scenario("default")
    draws = len(_draw_order(part))
    if outcome is None or outcome[0] == "error":
        observed = f"calling it failed: {outcome[2] if outcome else _error(run, events)}"
    else:
        observed = f"with rolls 0.5, 0.95, 0.3, 0.0777 it drew {draws} time(s) and returned {outcome[2]!r}"
    s.record("returns_roll", outcome is not None and outcome[0] == "result" and outcome[2] == 0.0777 and draws == 4,
             observed, "it draws 4 times and returns 0.0777, the first roll below likelihood=0.1")

    outcome, part = scenario("likelihood")
    draws = len(_draw_order(part))
    if outcome is None or outcome[0] == "error":
        observed = f"calling it failed: {outcome[2] if outcome else _error(run, events)}"
    else:
        observed = f"with likelihood=0.4 and rolls 0.5, 0.35 it drew {draws} time(s) and returned {outcome[2]!r}"
    s.record("likelihood_param", outcome is not None and outcome[0] == "result" and outcome[2] == 0.35 and draws == 2,
             observed, "it returns 0.35 after 2 draws (0.35 < 0.4)")

    outcome, part = scenario("gather")
    order = _draw_order(part)
    if outcome is None or outcome[0] == "error":
        observed = f"asyncio.gather of two calls failed: {outcome[2] if outcome else _error(run, events)}"
    else:
        observed = f"asyncio.gather of two calls drew in the order {_describe_order(order)}"
    s.record("yields_between_draws", outcome is not None and outcome[0] == "result" and interleaved(order), observed,
             "the second call draws while the first is still retrying (e.g. 1 2 1 2 1 1 1), "
             "because each call awaits between draws")


def _example(s: GradingSession, name: str, runs_check: str, concurrent_check: str) -> list | None:
    """Run example ``name`` with the example plans; record ``runs_check`` and ``concurrent_check``; return the trace."""
    module = _example_module(s, name)
    if module is None:
        s.record(runs_check, False, f"there is no minimalist_package/{name}.py",
                 f"{FOLDER}/minimalist_package/{name}.py")
        return None
    run, events = _run(s, "module", module, EXAMPLE_PLANS, name)
    order = _draw_order(events)
    tasks = len(set(order))
    ok = run.returncode == 0 and not run.timed_out and not run.traceback.strip() and tasks >= 2
    if run.returncode == 0 and not run.timed_out and tasks < 2:
        observed = f"'python -m {module}' exited 0, but {tasks} task(s) drew random numbers"
    else:
        observed = f"'python -m {module}': {_error(run, events) if run.returncode else run.describe()}"
    s.record(runs_check, ok, observed, "it exits 0 without a traceback after two tasks called unlikely_to_return")
    if not ok:
        return None
    seconds = max((e[3] for e in events if e[0] == "draw"), default=0.0) - min(
        (e[3] for e in events if e[0] == "draw"), default=0.0)
    s.record(concurrent_check, interleaved(order),
             f"draws by task: {_describe_order(order)} (tasks retried {len(order) - tasks} times in all, "
             f"over {seconds:.1f} s)",
             "task 2 draws while task 1 is still retrying (1 2 1 2 1 1 ...): with 0.1 s sleeps the run takes about "
             "as long as the slower task, not the sum of both")
    return events


def grade(s: GradingSession) -> None:
    """Probe the coroutine, then run both examples with known rolls (about 3 s in all)."""
    _probe(s)

    events = _example(s, "async_await_example", "await_runs", "await_concurrent")
    if events is not None:
        first, second = result_mentions(events, 0), result_mentions(events, 1)
        order = _draw_order(events)
        finished_first = "task 2" if _last_draw(events, 1) < _last_draw(events, 0) else "task 1"
        if not first or not second:
            missing = " and ".join(f"task {i + 1}'s ({EXAMPLE_RESULTS[i]})" for i, m in enumerate((first, second))
                                   if not m)
            observed = f"it never printed {missing} result"
        else:
            observed = (f"{finished_first} finished first; task {1 if first[0] < second[0] else 2}'s result "
                        "was printed first")
        s.record("await_order", bool(first and second and first[0] < second[0] and order), observed,
                 f"task 1's result ({EXAMPLE_RESULTS[0]}) printed before task 2's ({EXAMPLE_RESULTS[1]}), "
                 "even though task 2 finishes first")

    events = _example(s, "async_callback_example", "callback_runs", "callback_concurrent")
    if events is not None:
        second = result_mentions(events, 1)
        last_first = _last_draw(events, 0)
        if not second:
            observed = f"it never printed task 2's result ({EXAMPLE_RESULTS[1]})"
        elif second[0] < last_first:
            observed = "task 2's result was printed while task 1 was still retrying"
        else:
            observed = "task 2's result was printed only after task 1 had finished"
        s.record("callback_as_completed", bool(second) and second[0] < last_first, observed,
                 f"task 2's result ({EXAMPLE_RESULTS[1]}) printed as soon as task 2 ends, "
                 "before task 1's last roll")
