"""The log records a learner's process wrote to its console: what ``/rosout`` may not have carried.

A node that logs and then exits at once can take its last records with it. rclpy publishes each record
on ``/rosout`` (reliable, transient local) and also writes it to the console (stderr, in rcutils'
default ``RCUTILS_CONSOLE_OUTPUT_FORMAT``, ``[{severity}] [{time}] [{name}]: {message}``). A reliable
sample that DDS lost is repaired after the writer's next heartbeat (Fast DDS: 3 s); once the process
has exited there is no writer left to repair it, so the record never reaches the grader's subscription,
however long it waits. The console copy is whole: an actions-client reference that logged its result
as its last record and exited lost it on ``/rosout`` alone, in one ``dev validate`` run of several
hundred (its process's stderr held it).

Kept out of :mod:`ros2course.kit.records` on purpose: a grader's figures are fingerprinted per kit
module it imports (:mod:`ros2course.grade.fingerprint`); this step is used by the actions-client grader
only, so far.
"""

from __future__ import annotations

import re
from typing import Any

#: One console record's first line: severity, time (seconds since the epoch), logger name, message.
HEADER = re.compile(r"^\[(DEBUG|INFO|WARN|ERROR|FATAL)\] \[-?[0-9.]+\] \[([^\]]*)\]: ?(.*)$")


def one_line(text: str) -> str:
    """``text`` with every run of white space (new lines too) made one space, stripped."""
    return " ".join(text.split())


def console_records(output: str, node: str) -> list[str]:
    """The messages logger ``node`` wrote in ``output`` (a process's console text), oldest first, each on
    one line (:func:`one_line`; the lines after a record's first that start no record of their own are its
    message's). Lines that are no record (a ``print()``, a traceback) end the record before them only when
    they start with ``[``; otherwise they are taken as the message's next line (the console cannot tell)."""
    found: list[str] = []
    current: list[str] | None = None
    for line in output.splitlines():
        header = HEADER.match(line)
        if header is not None:
            if current is not None:
                found.append(one_line("\n".join(current)))
            current = [header.group(3)] if header.group(2) == node else None
        elif current is not None:
            if line.startswith("["):
                found.append(one_line("\n".join(current)))
                current = None
            else:
                current.append(line)
    if current is not None:
        found.append(one_line("\n".join(current)))
    return found


def log_texts(rosout: Any, node: str, proc: Any | None = None) -> list[str]:
    """Logger ``node``'s records, oldest first, one line each: those ``/rosout`` carried, and, when ``proc``
    (a :class:`~ros2course.run.process.LearnerProcess`) is given, the records its console (stderr) holds
    after the last of them (records lost with a process that exited; see the module docstring).

    Only records after the last one ``/rosout`` carried are added, never one before it, so a record is
    never counted twice; when the console does not hold that last record (its output was cut in the
    middle, or the node logs to another stream), nothing is added.

    Args:
        rosout: the session's :class:`~ros2course.run.probes.RosoutProbe`.
        node: the logger's name (a node's name, no namespace: ``my_node``).
        proc: the learner's process that runs ``node``, or None for ``/rosout`` alone.
    """
    carried = [one_line(r.msg) for r in rosout.records(node=node)]
    if proc is None:
        return carried
    console = console_records(proc.stderr(), node)
    if not carried:
        return console
    for index in range(len(console) - 1, -1, -1):
        if console[index] == carried[-1]:
            return carried + console[index + 1:]
    return carried
