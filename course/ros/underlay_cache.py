"""A machine-wide cache of built underlays, so a second install (a fresh clone, a new venv) skips the build.

An underlay build (:mod:`ros2course.ros.underlay_build`) takes minutes on 2 cores
(the Jazzy pieces about 5, SmartArmStack about 4), and every fresh venv paid it
again although the sources, the wheels and the interpreter were the same. After
a successful build the prefix is copied into
``<cache>/underlay/<component>-<key>/`` (``<cache>`` is
:func:`ros2course.files.cache_dir`), and a later build of the same key in another
install restores it instead of running colcon.

The key (:func:`portable_key`) is what the build's output depends on and
nothing else: the pins, the repairs version, the exact interpreter (version and
base prefix, whose ``libpython`` the C++ libraries link), the platform, and the
name and version of every ``ros-jazzy-*`` wheel installed (the headers and
libraries the build compiled against). The install's own paths are not in it:
they are *relocated*. The installed text files name their prefix, the prefix
of what they were built on and the venv (colcon's setup scripts, the
``parent_prefix_path`` resources, the console scripts' shebangs, CMake
exports); :func:`restore` rewrites those paths, as conda relocates a package's
text files. Binary files keep the old paths only where they do no harm: the
compiler's ``__FILE__`` strings in log messages (checked on the Jazzy and sas
builds: their ELF ``RUNPATH`` names only the interpreter's ``libpython``
folder and, for sas, its own ``lib/``, which the activation also puts on
``LD_LIBRARY_PATH``, searched before ``RUNPATH``). Byte-code caches are dropped,
as they hold the old source paths.

Not in the key: system headers (Eigen 3, Qt 5 for sas) and the compiler,
which a Debian upgrade could change; ``ros2course env --build --rebuild``
builds from source again and replaces the entry. ``ROS2COURSE_UNDERLAY_CACHE=0``
turns the cache off.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import hashlib
import json
import os
import shutil
import sys
import sysconfig
from pathlib import Path

from ros2course.files import cache_dir
from ros2course.ros.underlay_pins import REPAIRS_VERSION, Pin

#: Environment variable: ``0`` turns the cache off (build from source every time).
CACHE_VAR = "ROS2COURSE_UNDERLAY_CACHE"
#: Entries kept per component (the newest); older ones are removed when one is saved.
KEEP = 2
ORIGIN = "origin.json"
#: Bytes read to tell a text file from a binary one (a NUL byte in them: binary), as git and grep do.
_SNIFF = 8192


def enabled() -> bool:
    """True unless ``ROS2COURSE_UNDERLAY_CACHE=0`` (or ``false``/``no``/``off``)."""
    return os.environ.get(CACHE_VAR, "1").strip().lower() not in ("0", "false", "no", "off")


def folder() -> Path:
    """``<cache>/underlay``, where the entries are."""
    return cache_dir() / "underlay"


def wheel_versions() -> list[tuple[str, str]]:
    """``[(name, version)]`` of the installed ROS 2 wheels (``ros-jazzy-*``), sorted; empty with a system ROS."""
    import importlib.metadata  # noqa: PLC0415 - only a build reads it; every check imports this module

    found = {(dist.metadata["Name"] or "").lower(): dist.version for dist in importlib.metadata.distributions()}
    return sorted((name, version) for name, version in found.items() if name.startswith("ros-jazzy-"))


def portable_key(component: str, pins: tuple[Pin, ...], below: str = "") -> str:
    """16 hex digits naming a build by what its output depends on, never by where it is installed.

    Args:
        component: the component's name (``jazzy``, ``sas``, ``nav2``).
        pins: what is built.
        below: the portable key of the component it is built on ("" for jazzy).
    """
    data = {
        "component": component,
        "pins": [dataclasses.asdict(pin) for pin in pins],
        "repairs": REPAIRS_VERSION,
        "python": sys.version,
        "base_prefix": sys.base_prefix,
        "platform": sysconfig.get_platform(),
        "wheels": wheel_versions(),
        "below": below,
    }
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()[:16]


def lookup(component: str, key: str) -> Path | None:
    """The cache entry of ``component`` built as ``key`` (:func:`portable_key`), if one is complete."""
    entry = folder() / f"{component}-{key}"
    return entry if (entry / ORIGIN).is_file() and (entry / "prefix").is_dir() else None


def save(prefix: Path, component: str, key: str, paths: dict[str, str]) -> Path | None:
    """Copy a finished build into the cache; returns the entry, or None when it could not be written.

    Args:
        prefix: the build's install prefix.
        component: its component's name.
        key: its :func:`portable_key`.
        paths: the absolute paths the build's files name, by role (``prefix``,
            ``below``, ``venv``): :func:`restore` replaces each with the same
            role's path in the install it restores into.

    Never raises for a full disk or a read-only cache: the build itself succeeded
    and stays (the cache is an optimisation). Writes into a temporary folder and
    renames it, so a reader never sees half an entry.
    """
    if not enabled():
        return None
    entry = folder() / f"{component}-{key}"
    if lookup(component, key) is not None:
        return entry
    tmp = folder() / f".{component}-{key}.{os.getpid()}"
    try:
        tmp.mkdir(parents=True, exist_ok=False)
        shutil.copytree(prefix, tmp / "prefix", symlinks=True,
                        ignore=shutil.ignore_patterns("__pycache__"))
        origin = {"paths": paths, "saved": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}
        (tmp / ORIGIN).write_text(json.dumps(origin, indent=1), encoding="utf-8")
        os.replace(tmp, entry)
    except OSError:
        shutil.rmtree(tmp, ignore_errors=True)
        return None
    _prune(component)
    return entry


def _prune(component: str) -> None:
    """Keep the :data:`KEEP` newest entries of ``component``."""
    entries = sorted((p for p in folder().glob(f"{component}-*") if (p / ORIGIN).is_file()),
                     key=lambda p: p.stat().st_mtime, reverse=True)
    for stale in entries[KEEP:]:
        shutil.rmtree(stale, ignore_errors=True)


def _relocate_file(path: Path, pairs: list[tuple[bytes, bytes]]) -> bool:
    """Rewrite the old paths of one text file in place (mode kept); binary files are left alone."""
    with open(path, "rb") as handle:
        data = handle.read()
    if b"\0" in data[:_SNIFF]:
        return False
    new = data
    for old, now in pairs:
        new = new.replace(old, now)
    if new == data:
        return False
    with open(path, "wb") as handle:  # truncating in place keeps the file's mode (console scripts stay executable)
        handle.write(new)
    return True


def restore(entry: Path, prefix: Path, paths: dict[str, str]) -> int:
    """Copy a cache entry to ``prefix`` (which must not exist) and relocate it; returns the files rewritten.

    Args:
        entry: from :func:`lookup`.
        prefix: the new install prefix.
        paths: the new install's paths by role (the roles :func:`save` recorded).

    Raises:
        OSError: the copy failed (the caller removes ``prefix`` and builds from source).
        ValueError: the entry's origin record is unreadable.
    """
    origin = json.loads((entry / ORIGIN).read_text(encoding="utf-8"))
    old_paths = origin["paths"]
    # longest first: the build prefix lies inside the venv, and the venv's path must not be replaced inside it first
    pairs = sorted(((old.encode(), paths[role].encode()) for role, old in old_paths.items()
                    if old and paths.get(role) and old != paths[role]), key=lambda pair: -len(pair[0]))
    shutil.copytree(entry / "prefix", prefix, symlinks=True)
    rewritten = 0
    for top, dirs, files in os.walk(prefix):  # symlinks to folders are listed in dirs, never followed
        for name in [*files, *(d for d in dirs if (Path(top) / d).is_symlink())]:
            path = Path(top) / name
            if path.is_symlink():
                target = os.readlink(path).encode()
                moved = target
                for old, now in pairs:
                    moved = moved.replace(old, now)
                if moved != target:
                    path.unlink()
                    path.symlink_to(moved.decode())
                    rewritten += 1
            elif _relocate_file(path, pairs):
                rewritten += 1
        for name in [d for d in dirs if d == "__pycache__"]:
            shutil.rmtree(Path(top) / name, ignore_errors=True)
            dirs.remove(name)
    with contextlib.suppress(OSError):
        os.utime(entry)  # the entry was used: _prune keeps the newest
    return rewritten
