"""What a package's sources are, by content: the build's own record of what it built (issue 36).

colcon, CMake and setuptools' ``build_py`` decide what to rebuild by modification
time: a file rebuilds only when it is newer than what was built from it. Files that
arrive keeping an older time (``unzip``, ``tar x``, ``cp -a``, ``rsync -a``, a restore
from backup) or dated in the future (clock skew) are then skipped, deleted files keep
their installed copies, and the build holds code the learner no longer has.

So the engine reads every source file's bytes and mode (:func:`scan_package`) and keeps,
per package it built, what it built from (:class:`PackageRecord`). :func:`rebuild_reason`
compares the sources now with that record and says whether colcon's own incremental
build can be trusted (every change is dated after the last build) or the package must
be rebuilt from clean, and why.

Why our own walk and not a library: the rule is the build tools' (a change must be
newer than their outputs), and we need each file's bytes, mode and time in one pass
with the caches colcon ignores left out; ``hashlib`` does the hashing.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import stat
import time
from pathlib import Path

from ros2course.errors import NotGradable

#: Folders that are caches or version control, never sources (colcon's and setuptools' own outputs included).
SKIPPED_DIRS = frozenset({"__pycache__", ".git", ".hg", ".svn", ".pytest_cache", ".mypy_cache", ".ruff_cache"})
#: A source file larger than this (bytes) is refused: src/ is for sources, and reading it on every check costs.
MAX_SOURCE_BYTES = 64 * 1024 * 1024
_CHUNK = 1024 * 1024


@dataclasses.dataclass(frozen=True)
class SourceFile:
    """One file of a package as last read: content hash (sha256 hex), permission bits, mtime (ns since the epoch)."""

    sha256: str
    mode: int
    mtime_ns: int


@dataclasses.dataclass
class PackageSources:
    """A package's source tree now.

    Attributes:
        folder: the package folder, relative to the workspace root (``src/...``).
        files: relative path (POSIX, from the package folder) -> :class:`SourceFile`.
    """

    folder: str
    files: dict[str, SourceFile]

    @property
    def digest(self) -> str:
        """sha256 over every file's path, mode and content hash (times left out: a copy has the same digest)."""
        h = hashlib.sha256()
        for rel in sorted(self.files):
            f = self.files[rel]
            h.update(f"{rel}\0{f.mode:o}\0{f.sha256}\n".encode())
        return h.hexdigest()

    @property
    def content_digest(self) -> str:
        """sha256 over every file's path and content hash: neither times nor permission bits, which a copy or a
        hand-in changes (the seed of :attr:`ros2course.grade.session.GradingSession.random`)."""
        h = hashlib.sha256()
        for rel in sorted(self.files):
            h.update(f"{rel}\0{self.files[rel].sha256}\n".encode())
        return h.hexdigest()

    @property
    def newest_ns(self) -> int:
        """The newest mtime among the files (ns), 0 for an empty package."""
        return max((f.mtime_ns for f in self.files.values()), default=0)


def _refuse(path: Path, why: str, hint: str) -> NotGradable:
    return NotGradable(f"cannot read the sources: {path}: {why}", hint)


def _hash_file(path: Path, st: os.stat_result) -> str:
    if st.st_size > MAX_SOURCE_BYTES:
        raise _refuse(path, f"{st.st_size / 2**20:.0f} MiB, more than a source file may hold "
                            f"({MAX_SOURCE_BYTES // 2**20} MiB)",
                      "move large data out of src/ (or out of the package); the build reads every file there")
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as handle:
            while chunk := handle.read(_CHUNK):
                digest.update(chunk)
    except OSError as exc:
        raise _refuse(path, exc.strerror or str(exc), f"make it readable (chmod u+r {path}) or remove it") from exc
    return digest.hexdigest()


def scan_package(workspace_root: Path, folder: Path) -> PackageSources:
    """Read every file of the package in ``folder``: its bytes (hashed), mode and mtime.

    Symbolic links are followed, as colcon, CMake and setuptools follow them; caches and
    version-control folders (:data:`SKIPPED_DIRS`, ``*.egg-info``, ``*.pyc``) are left out.
    Nothing is modified.

    Args:
        workspace_root: the colcon workspace (``folder`` is recorded relative to it).
        folder: the package folder (holding ``package.xml``).

    Raises:
        NotGradable: a file cannot be read (permissions), is not a regular file (a fifo, a
            device), is larger than :data:`MAX_SOURCE_BYTES`, or a symbolic link loops; the
            message names the file. Never a partial result.
    """
    files: dict[str, SourceFile] = {}
    seen_dirs: set[tuple[int, int]] = set()

    def walk(directory: Path, rel: str) -> None:
        try:
            st_dir = directory.stat()
        except OSError as exc:
            raise _refuse(directory, exc.strerror or str(exc), f"fix or remove {directory}") from exc
        key = (st_dir.st_dev, st_dir.st_ino)
        if key in seen_dirs:
            raise _refuse(directory, "a symbolic link loop (this folder contains itself)",
                          f"remove the link that points back up: ls -l {directory.parent}")
        seen_dirs.add(key)
        try:
            entries = sorted(os.scandir(directory), key=lambda e: e.name)
        except OSError as exc:
            raise _refuse(directory, exc.strerror or str(exc), f"make it readable (chmod u+rx {directory})") from exc
        for entry in entries:
            path = Path(entry.path)
            name = f"{rel}{entry.name}"
            try:
                st = os.stat(entry.path)  # follows links
            except OSError as exc:
                why = "a symbolic link loop" if exc.errno == 40 else (
                    "a broken symbolic link" if entry.is_symlink() else exc.strerror or str(exc))
                raise _refuse(path, why, f"fix or remove {path}") from exc
            if stat.S_ISDIR(st.st_mode):
                if entry.name in SKIPPED_DIRS or entry.name.endswith(".egg-info"):
                    continue
                walk(path, name + "/")
            elif stat.S_ISREG(st.st_mode):
                if entry.name.endswith(".pyc"):
                    continue
                files[name] = SourceFile(_hash_file(path, st), stat.S_IMODE(st.st_mode), st.st_mtime_ns)
            else:
                raise _refuse(path, "not a regular file (a fifo, socket or device)", f"remove {path} from the package")
        seen_dirs.discard(key)

    walk(folder, "")
    try:
        relative = folder.relative_to(workspace_root).as_posix()
    except ValueError:
        relative = str(folder)
    return PackageSources(relative, files)


@dataclasses.dataclass
class PackageRecord:
    """What the engine last built of one package (kept in ``build/`` with colcon's own state).

    Attributes:
        folder: the package folder it was built from, relative to the workspace root.
        digest: :attr:`PackageSources.digest` of the sources built.
        files: relative path -> ``[sha256, mode, mtime_ns]`` of each file built.
        built_ns: wall-clock time (ns) the build ended; with the newest source time, the
            time a change must be newer than for colcon to see it.
        complete: False while the build runs: a record left so was interrupted (Ctrl+C,
            a killed check) and its build tree may be half written.
        failed: colcon ended with an error: the build tree is consistent, but not up to date.
    """

    folder: str
    digest: str
    files: dict[str, list]
    built_ns: int
    complete: bool = True
    failed: bool = False

    @classmethod
    def of(cls, sources: PackageSources, complete: bool = True, failed: bool = False) -> PackageRecord:
        """The record of ``sources`` as built now (the build's end: call it when colcon has ended)."""
        return cls(sources.folder, sources.digest,
                   {rel: [f.sha256, f.mode, f.mtime_ns] for rel, f in sources.files.items()},
                   time.time_ns(), complete, failed)

    @classmethod
    def from_json(cls, data: object) -> PackageRecord | None:
        """The record stored as ``data``; None when it is not one (an older format, a damaged file)."""
        try:
            return cls(str(data["folder"]), str(data["digest"]), dict(data["files"]), int(data["built_ns"]),
                       bool(data.get("complete", True)), bool(data.get("failed", False)))
        except (TypeError, KeyError, ValueError):
            return None

    @property
    def horizon_ns(self) -> int:
        """The time (ns) a changed file must be newer than for an incremental build to see it:
        the later of the build's end and the newest source it built (a file dated in the future
        made outputs dated in the future)."""
        newest = max((int(entry[2]) for entry in self.files.values()), default=0)
        return max(self.built_ns, newest)


def _listed(names: list[str], limit: int = 3) -> str:
    shown = ", ".join(names[:limit])
    return shown + (f" and {len(names) - limit} more" if len(names) > limit else "")


def rebuild_reason(record: PackageRecord | None, sources: PackageSources, built: bool) -> str | None:
    """Why ``sources`` must be rebuilt from clean rather than by colcon's incremental build, or None.

    The rule (issue 36): an incremental build reflects the files present only when every file
    added or changed since the last build is dated after it, none was removed, and the package
    did not move. Otherwise colcon would skip the older files, keep the removed ones installed,
    or refuse a build tree made for another folder.

    Args:
        record: what the engine last built of this package (None: no record).
        sources: the package's sources now (:func:`scan_package`).
        built: colcon's ``build/<pkg>`` or ``install/<pkg>`` exists (something to be stale).

    Returns:
        a clause for the learner ("sources changed but were older than the last build:
        setup.py"), or None when an incremental build (or no build at all) is right.
    """
    if not built:
        return None
    if record is None:
        return "built before without ros2course's record of its sources (which files it holds is unknown)"
    if not record.complete:
        return "its last build was interrupted before it ended"
    if record.folder != sources.folder:
        return f"it moved from {record.folder} to {sources.folder}"
    if record.digest == sources.digest:
        return None
    removed = sorted(set(record.files) - set(sources.files))
    if removed:
        return f"files were removed since the last build (their installed copies would stay): {_listed(removed)}"
    horizon = record.horizon_ns
    older = sorted(rel for rel, f in sources.files.items()
                   if (rel not in record.files or list(record.files[rel][:2]) != [f.sha256, f.mode])
                   and f.mtime_ns <= horizon)
    if older:
        future = record.horizon_ns > record.built_ns + 1_000_000_000
        why = ("the last build held files dated in the future (clock skew?), so no change can be seen by its time"
               if future else "sources changed but were older than the last build")
        return f"{why}: {_listed(older)}"
    return None
