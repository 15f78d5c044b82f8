"""The quote publisher's contract, shared by the parameters, launch-files and param-dump-load graders (seed ch. 22, 24).

Contract names come from shared/LESSONS.md; the launch file's values from the
seed's ch. 22.9 listing.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from course.grade.engine import GradingSession
from graders.kit.packages import source_package

PACKAGE = "python_package_that_uses_parameters_and_launch_files"
EXECUTABLE = "amazing_quote_configurable_publisher_node"
NODE = "amazing_quote_configurable_publisher_node"
INTERFACES = "package_with_interfaces"

#: Parameters the node declares and their defaults (seed ch. 22.3).
DEFAULTS: dict[str, Any] = {
    "quote": "Use the force, Pikachu!",
    "philosopher_name": "Uncle Ben",
    "topic_name": "amazing_quote",
    "period": 0.5,
}

#: The launch file of seed ch. 22.9.
LAUNCH_FILE = "peanut_butter_falcon_quote_publisher_launch.py"
LAUNCH_NODE = "peanut_butter_falcon_quote_publisher_node"
LAUNCH_TOPIC = "truly_inspirational_quote"
LAUNCH_PERIOD = 0.25  # seconds
LAUNCH_PHILOSOPHER = "Tyler"
LAUNCH_QUOTE = ("Yeah, you're gonna die, it's a matter of time. That ain't the question. The question's, "
                "whether they're gonna have a good story to tell about you when you're gone")
LAUNCH_PARAMETERS: dict[str, Any] = {
    "topic_name": LAUNCH_TOPIC,
    "period": LAUNCH_PERIOD,
    "quote": LAUNCH_QUOTE,
    "philosopher_name": LAUNCH_PHILOSOPHER,
}


def amazing_quote(s: GradingSession) -> type:
    """The workspace's ``package_with_interfaces/msg/AmazingQuote`` class (NotGradable if not built)."""
    return s.interface_type(INTERFACES, "msg", "AmazingQuote")


def short(text: str, limit: int = 70) -> str:
    """``text`` quoted, cut to ``limit`` characters."""
    return repr(text if len(text) <= limit else text[:limit - 3] + "...")


def first_difference(got: str, wanted: str) -> str:
    """Where ``got`` first differs from ``wanted``, e.g. ``differs at character 73: '...question.The'``."""
    if got == wanted:
        return "identical"
    index = len(os.path.commonprefix([got, wanted]))
    start = max(0, index - 15)
    return (f"differs from character {index + 1}: got {got[start:index + 15]!r}, "
            f"expected {wanted[start:index + 15]!r}")


def package_source(s: GradingSession) -> Path | None:
    """The learner's ``src/.../python_package_that_uses_parameters_and_launch_files`` folder, if any."""
    found = source_package(s, PACKAGE)
    return found[0] if found else None


def package_share(s: GradingSession) -> Path | None:
    """``share/<package>`` of the installed package, found the way ``ros2 launch`` finds it."""
    return s.find_share(PACKAGE)


def quote_after(s: GradingSession, check_id: str, probe: Any, since: float, *, count: int, period: float,
                quote: str, philosopher: str, proc: Any, expected: str, prefix: str = "", stale: str = "") -> bool:
    """Record ``check_id`` on the ``count``-th AmazingQuote message sent after ``since`` (wall clock, ``time.time()``).

    A parameter change must show within ``count`` messages (one may already be
    on its way when it is made: seed ch. 24.5); judged on send stamps
    (``TopicProbe.wait_sent_after``: up to ``count * period`` s plus
    ``LATE_DELIVERY``). Half the credit each for ``quote`` and ``philosopher``.

    Args:
        probe: the :class:`~course.run.probes.TopicProbe` of the quote topic.
        period: the publisher's period in seconds.
        proc: the publisher's process (the wait ends if it dies; its state is shown).
        prefix: opens the observed text (e.g. "set_parameters succeeded; ").
        stale: appended when a value did not change (a likely cause for the learner).
    """
    from graders.kit.nodes import process_state  # noqa: PLC0415

    with s.phase("observe"):
        later = probe.wait_sent_after(since, count, period, abort=lambda: proc.poll() is not None)
    if not later:
        return s.record(check_id, False, f"{prefix}no message after the change; {process_state(proc)}", expected)
    last = later[min(count, len(later)) - 1]
    quote_ok, name_ok = last.quote == quote, last.philosopher_name == philosopher
    seen = ", ".join(f"({short(m.quote, 30)}, {m.philosopher_name!r})" for m in later[:count])
    return s.record(check_id, quote_ok and name_ok,
                    f"{prefix}the next {len(later[:count])} message(s) were {seen}"
                    + ("" if quote_ok and name_ok else stale), expected, fraction=(quote_ok + name_ok) / 2)
