"""Helpers of the ``inspect-params`` grader (graders/inspect_params.py), a lesson of their own: when the script's
first ``ros2 param`` command came, what ``ros2 param get`` prints, and the dump file's placeholder.
"""

from __future__ import annotations

import contextlib
import os
import re
import threading
import time
from pathlib import Path
from typing import Any

#: The node a ``ros2 param`` command calls the node's services from: ``_ros2cli_<pid>`` (ros2cli
#: ``node/direct.py`` DirectNode; ``ros2param`` ``verb/*.py`` use it for every call). ``ros2 node list`` and
#: ``ros2 daemon start`` make none while a daemon answers; the daemon is ``_ros2cli_daemon_<domain>_<uuid>``.
PARAM_COMMAND_NODE = re.compile(r"_ros2cli_\d+")

#: ``ros2 param get`` prints ``<Type> value is: <value>`` (ros2param ``verb/get.py``), or the value alone with
#: ``--hide-type``.
GET_LINE = re.compile(r"^\s*(?:String|Integer|Double|Boolean) value is: ")
#: What :class:`DumpPlaceholder` writes into an absent dump file: a mapping of its own, which a dump appended
#: after it (``>>``) leaves in the file.
PLACEHOLDER = "ros2course_placeholder: this file is replaced by your script's ros2 param dump\n"


#: A line Fast DDS's logging wrote: its default consumer (StdoutConsumer, Fast DDS 2.14 as Jazzy ships it) prints
#: every log entry, errors included, on the process's **stdout**, coloured with ANSI escapes:
#: ``ESC[31;1m2026-12-03 ... [RTPS_TRANSPORT_SHM Error] Failed init_port fastrtps_port7413: open_and_lock_file
#: failed -> Function open_port_internal ESC[0m`` (Fast DDS docs, Logging > Consumers).
FASTDDS_LOG_LINE = re.compile(r"\x1b\[[0-9;]*m|\[[A-Z][A-Z0-9_]* (?:Error|Warning|Info)\]")


def without_fastdds_log(text: str) -> tuple[str, list[str]]:
    """``text`` (what a ``ros2`` command wrote on stdout, e.g. into a dump file) without the lines Fast DDS's
    logging put there (:data:`FASTDDS_LOG_LINE`), and those lines. ``ros2 param dump > file`` run while a shared-
    memory port of an ended participant is still locked writes such an error into the dump (fresh-clone CI of
    stop 74: ``dump_file`` lost as "not valid YAML" on an escape character): the middleware's words, not the
    script's."""
    kept, dropped = [], []
    for line in text.splitlines(keepends=True):
        (dropped if FASTDDS_LOG_LINE.search(line) else kept).append(line)
    return "".join(kept), [re.sub(r"\x1b\[[0-9;]*m", "", line).strip() for line in dropped]


def get_lines(line: str) -> str:
    """What of an output line is the value ``ros2 param get`` printed (``String value is: X`` -> ``X``)."""
    return GET_LINE.sub("", line.rstrip(), count=1)


class DumpPlaceholder:
    """The dump file before the script runs: the learner's own (kept as it is) or, when there is none, a
    placeholder written by the grader with the owner of its folder (the script may run as another user, and
    its ``>`` must be able to replace it). The lesson: "``ros2 param dump /node > cli/params_dump.yaml``,
    which overwrites it"; a script that appends (``>>``) keeps what was there.

    Args:
        path: the dump file in the workspace (``cli/params_dump.yaml``); its folder must exist for a placeholder.
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self.made = False
        self.before = ""
        if path.is_file():
            self.before = path.read_text(encoding="utf-8", errors="replace")
        elif path.parent.is_dir():
            path.write_text(PLACEHOLDER, encoding="utf-8")
            folder = path.parent.stat()
            with contextlib.suppress(PermissionError):
                os.chown(path, folder.st_uid, folder.st_gid)
            path.chmod(0o664)
            self.made, self.before = True, PLACEHOLDER

    def kept(self, text: str) -> bool:
        """Whether ``text`` (the file after the run, rewritten by it) still begins with what was there before."""
        return bool(self.before.strip()) and text != self.before and text.startswith(self.before)

    def untouched(self) -> bool:
        """Whether the file is still the grader's placeholder (the script never wrote it)."""
        return self.made and self.path.is_file() and self.path.read_text(encoding="utf-8", errors="replace") == PLACEHOLDER

    def remove_if_left(self) -> None:
        """Remove the placeholder when the script never replaced it: the learner's folder as it was."""
        if self.untouched():
            self.path.unlink()


class FirstParamCommand:
    """When the first ``ros2 param`` command's node (:data:`PARAM_COMMAND_NODE`) joins the graph of ``node``
    (an rclpy node), watched every 50 ms from a thread of its own (graph queries need no spinning)."""

    def __init__(self, node: Any) -> None:
        self._node = node
        self._stopped = threading.Event()
        self.seen: float | None = None  # time.monotonic() when it was first seen
        self._thread = threading.Thread(target=self._watch, name="first-param-command", daemon=True)
        self._thread.start()

    def _watch(self) -> None:
        while self.seen is None and not self._stopped.wait(0.05):
            names = self._node.get_node_names_and_namespaces()
            if any(PARAM_COMMAND_NODE.fullmatch(name) for name, _ in names):
                self.seen = time.monotonic()

    def stop(self) -> None:
        """Stop watching (returns once the thread has ended)."""
        self._stopped.set()
        self._thread.join()

    def seconds_after(self, start: float) -> float | None:
        """Seconds from ``start`` (``time.monotonic()``) to the first such node; None if none joined."""
        return None if self.seen is None else max(0.0, self.seen - start)
