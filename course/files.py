"""File helpers every layer of the engine may use (the bottom layer: imports nothing of the engine)."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` so readers see the old or the new file, never half of one."""
    atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` so readers see the old or the new file, never half of one
    (a temporary file beside it, mode 0600, renamed over it)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def cache_dir() -> Path:
    """The folder for ros2course's caches: ``ROS2COURSE_CACHE_DIR`` or platformdirs' user cache folder.

    Holds the kept catalog (:func:`ros2course.lesson.catalog.load_catalog`), the kept manifests and the
    built underlays (:mod:`ros2course.ros.underlay_cache`); ``~/.cache/ros2course`` on Linux.
    """
    override = os.environ.get("ROS2COURSE_CACHE_DIR")
    if override:
        return Path(override)
    from platformdirs import user_cache_path  # noqa: PLC0415 - platformdirs only when no cache folder is set (start time of list)

    return user_cache_path("ros2course", appauthor=False)
