"""Following colcon's console output in a build log, for a progress display.

Used by the lesson builds (:mod:`ros2course.builder.colcon`) and the underlay build
(:mod:`ros2course.ros.underlay_build`), so it sits in the ROS layer both may use.
"""

from __future__ import annotations

import contextlib
import re
import threading
from collections.abc import Callable
from pathlib import Path


class BuildProgress(threading.Thread):
    """Follows colcon's output in the build log and reports each package it starts and finishes.

    colcon's console_start_end event handler prints ``Starting >>> pkg`` and
    ``Finished <<< pkg [1.2s]`` (``Failed <<<``, ``Aborted <<<``) lines; each
    becomes a call ``report("building pkg (1 of 3 done)")`` for a progress display.

    Args:
        log_path: the build log being written.
        report: called from this thread with one short line.
        total: packages to build (for the "n of total" count; None: unknown).

    It reads from the log's size at construction, so an earlier pass in the same log is not reported again.
    """

    PATTERN = re.compile(r"^(Starting >>>|Finished <<<|Failed\s+<<<|Aborted\s+<<<)\s+(\S+)")

    def __init__(self, log_path: Path, report: Callable[[str], None], total: int | None) -> None:
        super().__init__(daemon=True, name="ros2course-build-progress")
        self.log_path, self.report, self.total = log_path, report, total
        self._offset = log_path.stat().st_size if log_path.is_file() else 0
        self._stop_event = threading.Event()

    def run(self) -> None:
        done, building = 0, []
        with contextlib.suppress(OSError), open(self.log_path, encoding="utf-8", errors="replace") as log:
            log.seek(self._offset)
            while True:
                line = log.readline()
                if not line:
                    if self._stop_event.wait(0.2):
                        return
                    continue
                match = self.PATTERN.match(line)
                if match is None:
                    continue
                verb, package = match.groups()
                if verb.startswith("Starting"):
                    building.append(package)
                else:
                    done += 1
                    building = [p for p in building if p != package]
                count = f"{done} of {self.total} done" if self.total else f"{done} done"
                self.report(f"building {', '.join(building) or '...'} ({count})")

    def stop(self) -> None:
        """Stop following (the thread ends within 0.2 s)."""
        self._stop_event.set()
        self.join(timeout=1.0)
