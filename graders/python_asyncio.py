"""Grader for ``python-asyncio`` (seed ch. 2.5): a coroutine and two ways to use its results.

Everything runs the learner's code for real, with ``python/minimalist_package``
as the working directory (as ``python -m`` is used in the tutorial), under the
wrapper ``graders/data/python_asyncio/wrapper.py``: it replaces
``random.random`` / ``random.uniform`` with a known sequence of rolls *per
asyncio task* (so the verdict does not depend on luck or on scheduling) and
records, in order, every roll drawn and every piece of text printed, with the
task that printed it (:mod:`graders._asyncio_trace`). The checks read that trace:

* concurrency is judged on the order of the draws (the second task draws
  while the first one is still retrying), never on wall-clock times;
* "await order" and "as it completes" are judged on where each result is
  printed relative to the other task's final draw.
"""

from __future__ import annotations

from pathlib import Path

from ros2course.kit import Check, Session, Unmet
from ._asyncio_trace import Trace, progress_lines, result_lines, run_traced

#: No continuous observation: each run ends by itself (about 1 s of asyncio.sleep at 0.1 s per retry).
WINDOW = 3.0

FOLDER = Path("python") / "minimalist_package"
WRAPPER = Path(__file__).resolve().parent / "data" / "python_asyncio" / "wrapper.py"

#: Rolls each task draws, by the order in which tasks first draw (further tasks reuse the last plan).
#: The first task retries 7 times, the second only twice, so the second one finishes first.
EXAMPLE_PLANS = [[0.52, 0.81, 0.67, 0.93, 0.58, 0.74, 0.85, 0.0312], [0.61, 0.77, 0.0687]]
#: The successful roll of each plan above: what each task must return.
EXAMPLE_RESULTS = [plan[-1] for plan in EXAMPLE_PLANS]
#: The plans the other way round, for a second run of each example: task 1 finishes first, task 2 last. Printing
#: every result after the last await (asyncio.gather), or awaiting only the first task, or sleeping instead of
#: awaiting, gives the first run's output (task 1 was the slower) but not this one's (audit of stop 71).
SWAPPED_PLANS = EXAMPLE_PLANS[::-1]
SWAPPED_RESULTS = [plan[-1] for plan in SWAPPED_PLANS]
#: Seconds a run may go on after its last draw (the reference ends within milliseconds; a sleep of its own
#: instead of awaiting the tasks, longer).
IDLE_AFTER = 0.5
#: The tags the examples give their two tasks, in creation order (the lesson's task1 and task2).
EXAMPLE_TAGS = ["task1", "task2"]
#: How close a printed number must be to a result to count as printing it (allows rounding to 2 decimals).
RESULT_TOLERANCE = 0.005
#: Median seconds between two draws of one call that count as the contract's `asyncio.sleep(0.1)`: from just
#: under 0.1 s (asyncio never ends a sleep early, so a pause is the sleep plus a print; the margin is clock
#: resolution) to half of it again (a loaded machine only lengthens a pause, and the median of the pauses drops the
#: odd late one; the reference measured 0.10 s with four busy loops on two cores). A sleep of 0 (or a negative
#: one, which asyncio treats as 0), of a second (issue 24's mutants `sleep(-1.1)` and `sleep(1.1)`), of 0.2 s or
#: of 0.05 s (issue 37's poodle held-out mutants, which passed the earlier range of 0.05-0.6 s) is outside.
PAUSE_RANGE = (0.09, 0.15)
#: Seconds each run may take before it is stopped (the reference needs about 1 s).
RUN_TIMEOUT = 20.0
#: The wrapper's probe scenarios with one result: (scenario, check, rolls as told, return value, draws, expected).
SCENARIOS = [("default", "returns_roll", "with rolls 0.5, 0.95, 0.3, 0.0777", 0.0777, 4,
              "it draws 4 times and returns 0.0777, the first roll below likelihood=0.1"),
             ("likelihood", "likelihood_param", "with likelihood=0.4 and rolls 0.5, 0.35", 0.35, 2,
              "it returns 0.35 after 2 draws (0.35 < 0.4)"),
             ("boundary", "default_likelihood", "with rolls 0.1, 0.0999", 0.0999, 2,
              "it draws twice and returns 0.0999: a roll of 0.1 is a miss (roll < likelihood, the default 0.1)")]

CHECKS = [
    Check("module", "minimalist_package.minimalist_async.unlikely_to_return is an async function", 1,
          "make python/minimalist_package/minimalist_package/minimalist_async.py with "
          "'async def unlikely_to_return(tag: str, likelihood: float = 0.1) -> float:'"),
    Check("returns_roll", "unlikely_to_return retries until a roll is below 0.1, and returns that roll", 2,
          "loop: draw random.uniform(0.0, 1.0); if it is below likelihood, return it; otherwise sleep and draw again",
          needs=("module",)),
    Check("prints_progress", "unlikely_to_return prints a retry line for each miss and '<tag> Done.' on success", 1,
          "print(f\"{tag} retry needed (roll = {roll} >= {likelihood}).\") before each sleep, "
          "print(f\"{tag} Done.\") before returning", needs=("module",)),
    Check("likelihood_param", "unlikely_to_return compares with its likelihood argument", 1,
          "compare the roll with the likelihood parameter, not with a fixed 0.1", needs=("module",)),
    Check("default_likelihood", "Its likelihood defaults to 0.1, and a roll equal to it is a miss", 1,
          "'likelihood: float = 0.1' in the signature, and return only when roll < likelihood (not <=)",
          needs=("module",)),
    Check("yields_between_draws", "Between draws it awaits asyncio.sleep, so two calls run concurrently", 2,
          "use 'await asyncio.sleep(0.1)', not time.sleep(0.1): time.sleep blocks every other task",
          needs=("module",)),
    Check("await_runs", "python -m ...async_await_example runs two tasks and exits 0", 1,
          "run it yourself from python/minimalist_package: python -m minimalist_package.async_await_example",
          needs=("module",), part="await"),
    Check("await_concurrent", "async_await_example runs its two tasks concurrently", 2,
          "create both tasks with asyncio.create_task() before awaiting the first one", needs=("await_runs",), part="await"),
    Check("await_order", "async_await_example prints the results in await order", 2,
          "await the tasks in the order you created them and print each result right after its await",
          needs=("await_runs",), part="await"),
    Check("await_result_lines", "async_await_example prints 'The result of task=<tag> was <result>.' for each task", 1,
          "after each await: print(f\"The result of task={tag} was {result}.\") with the tags task1 and task2",
          needs=("await_runs",), part="await"),
    Check("callback_runs", "python -m ...async_callback_example runs two tasks and exits 0", 1,
          "run it yourself from python/minimalist_package: python -m minimalist_package.async_callback_example",
          needs=("module",), part="callback"),
    Check("callback_concurrent", "async_callback_example runs its two tasks concurrently", 1,
          "create both tasks (and add their callbacks) before awaiting the first one", needs=("callback_runs",), part="callback"),
    Check("callback_as_completed", "async_callback_example prints each result as soon as its task ends", 2,
          "task.add_done_callback(partial(handle_return_callback, tag)) and print the result in the callback",
          needs=("callback_runs",), part="callback"),
    Check("callback_result_lines", "async_callback_example prints each result with its own task's tag", 1,
          "task.add_done_callback(partial(handle_return_callback, tag)): partial binds this task's tag now (a "
          "lambda that reads the loop variable when it runs sees the last tag, task2, for both)",
          needs=("callback_runs",), part="callback"),
]


def grade(s: Session) -> None:
    """Probe the coroutine, then run both examples with known rolls (about 3 s in all)."""
    _probe(s)
    with s.part("await"):
        trace, module = _example(s, "async_await_example", "await_runs", "await_concurrent")
        first, second = (trace.mentions(i, EXAMPLE_RESULTS[i], RESULT_TOLERANCE) for i in (0, 1))
        missing = " and ".join(f"task {i + 1}'s ({EXAMPLE_RESULTS[i]})" for i, m in enumerate((first, second))
                               if not m)
        finished_first = "task 2" if trace.last_draw(1) < trace.last_draw(0) else "task 1"
        swapped = _swapped(s, module, "async_await_example")
        early = swapped.mentions(0, SWAPPED_RESULTS[0], RESULT_TOLERANCE)
        right_after = bool(early) and early[0] < swapped.last_draw(1)
        s.record("await_order", bool(first and second) and first[0] < second[0] and right_after,
                 f"it never printed {missing} result{trace.cancelled(EXAMPLE_PLANS)}" if missing else
                 f"{finished_first} finished first; task {1 if first[0] < second[0] else 2}'s result was printed first"
                 if first[0] > second[0] or right_after else
                 "in await order; but when task 1 finished first, its result was printed only after task 2 had "
                 "finished too: each result must be printed right after its own await, not all after the last",
                 f"task 1's result ({EXAMPLE_RESULTS[0]}) printed before task 2's ({EXAMPLE_RESULTS[1]}), "
                 "even though task 2 finishes first; and, when task 1 finishes first, as soon as its await returns")
        result_lines(s, trace, "await_result_lines", list(zip(EXAMPLE_TAGS, EXAMPLE_RESULTS)), RESULT_TOLERANCE)
    with s.part("callback"):
        trace, module = _example(s, "async_callback_example", "callback_runs", "callback_concurrent")
        second, last_first = trace.mentions(1, EXAMPLE_RESULTS[1], RESULT_TOLERANCE), trace.last_draw(0)
        first = trace.mentions(0, EXAMPLE_RESULTS[0], RESULT_TOLERANCE)
        cancelled = trace.cancelled(EXAMPLE_PLANS)
        swapped = _swapped(s, module, "async_callback_example")
        done = [swapped.mentions(i, SWAPPED_RESULTS[i], RESULT_TOLERANCE) for i in (0, 1)]
        idle = swapped.idle_after_draws()
        waits_all = all(done) and done[0][0] < swapped.last_draw(1) and idle is not None and idle <= IDLE_AFTER
        s.record("callback_as_completed", bool(second and first) and second[0] < last_first and waits_all,
                 f"it never printed task 2's result ({EXAMPLE_RESULTS[1]}){cancelled}" if not second else
                 f"task 2's result was printed, but task 1's ({EXAMPLE_RESULTS[0]}) never was{cancelled}" if not first
                 else "task 2's result was printed only after task 1 had finished" if second[0] > last_first else
                 "task 2's result was printed while task 1 was still retrying" if waits_all else
                 "when task 1 finished first, task 2's result was never printed"
                 f"{swapped.cancelled(SWAPPED_PLANS)}" if not done[1] else
                 "when task 1 finished first, its result was never printed"
                 f"{swapped.cancelled(SWAPPED_PLANS)}" if not done[0] else
                 "when task 1 finished first, its result was printed only after task 2 had finished"
                 if done[0][0] >= swapped.last_draw(1) else
                 f"the run went on {idle or 0:.1f} s after its last task had returned: await the tasks themselves "
                 "(a sleep of your own is too short on a slow day, and too long on every other)",
                 f"each result printed as soon as its task ends, whichever ends first, and the run ends with its "
                 f"last task (within {IDLE_AFTER} s)")
        result_lines(s, trace, "callback_result_lines", list(zip(EXAMPLE_TAGS, EXAMPLE_RESULTS)),
                     RESULT_TOLERANCE)


def _probe(s: Session) -> None:
    """Import the coroutine and call it directly with known rolls: module, returns_roll, likelihood_param, yields."""
    folder = s.workspace_root / FOLDER
    if not (folder / "minimalist_package").is_dir():
        s.record("module", False, f"there is no folder {FOLDER / 'minimalist_package'} in the workspace",
                 "the package folder from the previous lesson")
        raise Unmet("no minimalist_package folder")
    run, trace = run_traced(s, WRAPPER, "probe", "minimalist_package.minimalist_async", [[0.5]], "asyncio_probe",
                            cwd=folder, timeout=RUN_TIMEOUT)
    found = trace.first("function")  # ["function", exists, is_coroutine]; None: the import failed
    is_coroutine = bool(found and found[2])
    observed = ("is an async def" if is_coroutine else "is a plain function (def), not a coroutine"
                if found and found[1] else "does not exist")
    s.record("module", is_coroutine, f"unlikely_to_return {observed}" if found else
             f"'import minimalist_package.minimalist_async' failed: {trace.error(run)}",
             "'async def unlikely_to_return(tag, likelihood=0.1)' in minimalist_async, importable from " + str(FOLDER))
    s.require("module")
    for name, check_id, rolls, value, draws, expected in SCENARIOS:
        outcome, part = trace.scenario(name)
        ok = outcome is not None and outcome[0] == "result"
        s.record(check_id, ok and outcome[2] == value and len(part.draw_order()) == draws,
                 f"{rolls} it drew {len(part.draw_order())} time(s) and returned {outcome[2]!r}" if ok else
                 f"calling it failed: {outcome[2] if outcome else trace.error(run)}", expected)
    progress_lines(s, trace.scenario("default")[1])
    outcome, part = trace.scenario("gather")
    ok = outcome is not None and outcome[0] == "result"
    pauses = sorted(part.pauses(0))
    pause = pauses[len(pauses) // 2] if pauses else None
    paced = pause is not None and PAUSE_RANGE[0] <= pause <= PAUSE_RANGE[1]
    paced_text = "" if pause is None else f"; the first call's draws were {pause:.2f} s apart (median)" + (
        "" if paced else ": the sleep between two draws is not the 0.1 s of the contract")
    blocking = part.blocking()
    paced_text += f"; it called time.sleep({blocking[0][2]}) between draws, which blocks every task" if blocking else ""
    s.record("yields_between_draws", ok and part.interleaved() and paced and not blocking,
             f"asyncio.gather of two calls drew in the order {part.describe_order()}{paced_text}" if ok else
             f"asyncio.gather of two calls failed: {outcome[2] if outcome else trace.error(run)}",
             "the second call draws while the first is still retrying (e.g. 1 2 1 2 1 1 1), "
             f"because each call awaits asyncio.sleep(0.1) between draws (pauses of {PAUSE_RANGE[0]}-"
             f"{PAUSE_RANGE[1]} s count)")


def _swapped(s: Session, module: str, name: str) -> Trace:
    """Run example ``module`` again with :data:`SWAPPED_PLANS` (task 1 finishes first); its trace."""
    return run_traced(s, WRAPPER, "module", module, SWAPPED_PLANS, f"{name}_swapped", cwd=s.workspace_root / FOLDER,
                      timeout=RUN_TIMEOUT)[1]


def _example(s: Session, name: str, runs_check: str, concurrent_check: str) -> tuple[Trace, str]:
    """Run example ``name`` with the example plans; record ``runs_check`` and ``concurrent_check``; return the trace
    and the module run (``minimalist_package.<name>``, or in the tutorial's subpackage).

    Raises:
        Unmet: the example is missing or did not run cleanly with two tasks (its part ends).
    """
    package = s.workspace_root / FOLDER / "minimalist_package"
    # flat in the package (this course) or in the tutorial's subpackage
    module = next((f"minimalist_package.{sub}{name}" for sub in ("", "minimalist_async.")
                   if (package / sub.replace(".", "/") / f"{name}.py").is_file()), None)
    if module is None:
        s.record(runs_check, False, f"there is no minimalist_package/{name}.py", f"{FOLDER}/minimalist_package/{name}.py")
        raise Unmet(f"there is no {name}.py")
    run, trace = run_traced(s, WRAPPER, "module", module, EXAMPLE_PLANS, name, cwd=package.parent, timeout=RUN_TIMEOUT)
    tasks = len(set(trace.draw_order()))
    clean = run.returncode == 0 and not run.timed_out and not run.traceback.strip()
    if not s.record(runs_check, clean and tasks >= 2,
                    f"'python -m {module}' exited 0, but {tasks} task(s) drew random numbers" if clean
                    else f"'python -m {module}': {trace.error(run) if run.returncode else run.describe()}",
                    "it exits 0 without a traceback after two tasks called unlikely_to_return"):
        raise Unmet(f"{name} did not run")
    sequential = "" if trace.interleaved() else (
        "; task 2 drew only after task 1 had returned: the calls ran one after the other (a coroutine awaited "
        "directly, or a task awaited right after its creation, runs to its end before the next line runs)")
    s.record(concurrent_check, trace.interleaved(),
             f"draws by task: {trace.describe_order()} (tasks retried {len(trace.draw_order()) - tasks} times in "
             f"all, over {trace.draw_seconds():.1f} s){sequential}",
             "task 2 draws while task 1 is still retrying (1 2 1 2 1 1 ...): with 0.1 s sleeps the run takes about "
             "as long as the slower task, not the sum of both")
    return trace, module
