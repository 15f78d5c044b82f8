"""Wrapper of ``python-asyncio`` (run by graders/python_asyncio.py instead of ``python -m``).

argv: trace file, mode (``probe`` or ``module``), module name, plans (JSON). It
replaces ``random.random`` / ``random.uniform`` with a known sequence of rolls
*per call* of ``unlikely_to_return`` (plan i for the i-th call that draws;
further calls reuse the last plan; a call is told apart by a context variable
its wrapper sets, so two calls awaited one after the other in one asyncio task
are two calls, not one task that never stops drawing), and records in order every roll drawn and every piece of text
printed, with the task that did it, into the trace file (a JSON list of
events, read by :mod:`graders._asyncio_trace`):

* ``["draw", task, value, seconds]``, ``["out", task or -1, text, seconds]``;
* ``["blocking", task, seconds asked, seconds]``: ``time.sleep`` called inside a task (it blocks the event loop:
  the lesson's "never time.sleep", seen even when an ``await asyncio.sleep(0)`` after it lets the draws alternate);
* ``["end", seconds]``: the module (or probe) returned, written last;
* ``["function", exists, is_coroutine]``, ``["scenario", name]``,
  ``["result", name, value]``, ``["error", name or mode, "Type: message"]``.

In ``probe`` mode it imports the module, checks ``unlikely_to_return`` and calls
it in four scenarios (default likelihood, likelihood=0.4, a roll equal to the default likelihood, two
calls gathered);
in ``module`` mode it runs the module as ``__main__``.
"""
import asyncio
import contextvars
import functools
import importlib
import inspect
import io
import json
import os
import random
import runpy
import sys
import time

TRACE, MODE, TARGET, PLANS = sys.argv[1], sys.argv[2], sys.argv[3], json.loads(sys.argv[4])
EXTRA_DRAWS = 30  # draws allowed after a plan ends (each then rolls 0.99) before giving up
sys.argv = [TARGET]
sys.path[0] = os.getcwd()  # what 'python -m' does
events = []
state = {"plans": PLANS, "tasks": {}, "counts": {}}
start = time.monotonic()


_call = contextvars.ContextVar("ros2course_call", default=None)


def _task():
    call = _call.get()
    if call is not None:
        return call
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
_real_sleep = time.sleep


def _sleep(seconds):
    index = _index(False)
    if index != -1:
        events.append(["blocking", index, seconds, time.monotonic() - start])
    return _real_sleep(seconds)


time.sleep = _sleep  # before the learner's import: `from time import sleep` gets this one too


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
    import importlib  # noqa: PLC0415 - the learner's module, imported when the probe runs
    module = importlib.import_module("minimalist_package.minimalist_async")
    function = getattr(module, "unlikely_to_return", None)
    events.append(["function", function is not None, inspect.iscoroutinefunction(function)])
    if not inspect.iscoroutinefunction(function):
        return
    scenarios = [
        ("default", [[0.5, 0.95, 0.3, 0.0777]], lambda: function(tag="probe")),  # the contract's parameter name
        ("likelihood", [[0.5, 0.35]], lambda: function("probe", likelihood=0.4)),
        ("boundary", [[0.1, 0.0999]], lambda: function("probe")),
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


def _count_calls():
    """Wrap ``unlikely_to_return`` so that each call draws from its own plan (see the module docstring)."""
    try:
        module = importlib.import_module("minimalist_package.minimalist_async")
    except Exception:  # noqa: BLE001 - the example's own import reports it
        return
    function = getattr(module, "unlikely_to_return", None)
    if not inspect.iscoroutinefunction(function):
        return

    @functools.wraps(function)
    async def call(*args, **kwargs):
        token = _call.set(object())
        try:
            return await function(*args, **kwargs)
        finally:
            _call.reset(token)
    module.unlikely_to_return = call


try:
    if MODE == "probe":
        _probe()
    else:
        _count_calls()
        runpy.run_module(TARGET, run_name="__main__", alter_sys=True)
except BaseException as exc:
    if not (isinstance(exc, SystemExit) and exc.code in (0, None)):
        events.append(["error", MODE, f"{type(exc).__name__}: {exc}"])
    raise
finally:
    events.append(["end", time.monotonic() - start])
    _dump()
