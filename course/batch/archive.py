"""Finding a class's submissions and copying each into a scratch workspace, safely.

A submissions folder holds one entry per student; the entry's name (without
``.zip`` / ``.tar.gz`` / ``.tgz``) is the student id. An entry is a colcon
workspace (a folder with ``src/``), a folder of packages (``package.xml``
somewhere below, no ``src/``), or an archive of either. The original is never
written to: it is copied (folders) or extracted (archives) into a fresh scratch
folder, and a folder of packages is placed under ``scratch/src/``.

Archives are extracted defensively: absolute member names, ``..`` components,
links that point outside the extraction folder, device files, more than
:data:`MAX_MEMBERS` members or more than :data:`MAX_UNPACKED_BYTES` unpacked
bytes make the submission "not gradable" with the reason.
"""

from __future__ import annotations

import dataclasses
import os
import re
import shutil
import stat
import tarfile
import zipfile
from pathlib import Path, PurePosixPath

from ros2course.builder.colcon import RECORDS
from ros2course.errors import NotGradable

#: Archive suffixes recognised, longest first.
ARCHIVE_SUFFIXES = (".tar.gz", ".tgz", ".zip")
#: Cap on the bytes an archive may unpack to (a zip bomb is "not gradable").
MAX_UNPACKED_BYTES = 500 * 1024 * 1024
#: Cap on the number of members of an archive.
MAX_MEMBERS = 20_000
#: Folders of a copied workspace left out: ros2course's own check logs of the student's machine.
_SKIP_DIRS = {"__pycache__", ".git"}
_SAFE_ID = re.compile(r"[^A-Za-z0-9._@+-]")


@dataclasses.dataclass(frozen=True)
class Submission:
    """One entry of the submissions folder.

    Attributes:
        student: the student id (entry name without archive suffix), made safe for a folder name.
        path: the entry (folder or archive), absolute.
        problem: why it cannot be graded at all (e.g. "not a folder or archive"), "" when it may be.
    """

    student: str
    path: Path
    problem: str = ""


def student_id(name: str) -> str:
    """The student id of an entry name: archive suffix removed, unsafe characters replaced by ``_``."""
    for suffix in ARCHIVE_SUFFIXES:
        if name.lower().endswith(suffix):
            name = name[: -len(suffix)]
            break
    safe = _SAFE_ID.sub("_", name).strip(".") or "_"
    return safe


def discover(folder: Path) -> list[Submission]:
    """Every entry of ``folder`` (hidden entries skipped), sorted by student id.

    Entries that are neither a folder nor a known archive, and a second entry
    with an id already taken, come back with a ``problem``.

    Raises:
        NotGradable: never; a ``CourseError`` (bad input) is raised by the caller when ``folder`` is not a folder.
    """
    out: list[Submission] = []
    seen: set[str] = set()
    for entry in sorted(folder.iterdir(), key=lambda p: p.name):
        if entry.name.startswith("."):
            continue
        sid = student_id(entry.name)
        path = entry.absolute()
        problem = ""
        if sid in seen:
            problem = f"duplicate student id {sid!r} ({entry.name})"
            sid = f"{sid}__{entry.name}"
            sid = _SAFE_ID.sub("_", sid)
        elif entry.is_symlink() and not entry.exists():
            problem = "a dangling symbolic link"
        elif not entry.is_dir() and not entry.name.lower().endswith(ARCHIVE_SUFFIXES):
            problem = f"{entry.name} is not a folder, a .zip or a .tar.gz archive"
        seen.add(sid)
        out.append(Submission(sid, path, problem))
    return sorted(out, key=lambda s: s.student)


def _member_ok(name: str) -> str:
    """Why an archive member name is refused ("" when fine)."""
    pure = PurePosixPath(name.replace("\\", "/"))
    if pure.is_absolute() or name.startswith(("/", "\\")) or re.match(r"^[A-Za-z]:", name):
        return f"absolute path {name!r}"
    if ".." in pure.parts:
        return f"path escaping the archive {name!r}"
    return ""


def extract_zip(archive: Path, dest: Path) -> None:
    """Extract a zip into ``dest`` after checking every member.

    Raises:
        NotGradable: unreadable zip, unsafe member name, too many members or bytes.
    """
    try:
        with zipfile.ZipFile(archive) as zf:
            infos = zf.infolist()
            if len(infos) > MAX_MEMBERS:
                raise NotGradable(f"the archive has {len(infos)} members (at most {MAX_MEMBERS})")
            total = 0
            for info in infos:
                problem = _member_ok(info.filename)
                if problem:
                    raise NotGradable(f"unsafe archive member: {problem}", "re-create the archive from the workspace folder")
                total += info.file_size
                if total > MAX_UNPACKED_BYTES:
                    raise NotGradable(f"the archive unpacks to more than {MAX_UNPACKED_BYTES} bytes")
            for info in infos:
                mode = info.external_attr >> 16
                if stat.S_ISLNK(mode):
                    continue  # links are not extracted: they could point anywhere
                target = dest / info.filename
                if info.is_dir():
                    target.mkdir(parents=True, exist_ok=True)
                    continue
                target.parent.mkdir(parents=True, exist_ok=True)
                written = 0
                with zf.open(info) as src, open(target, "wb") as out:
                    while chunk := src.read(1 << 20):
                        written += len(chunk)
                        if written > info.file_size or written > MAX_UNPACKED_BYTES:
                            raise NotGradable("an archive member unpacks to more than its declared size")
                        out.write(chunk)
                if mode & 0o111:
                    target.chmod(0o755)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, OSError, EOFError, NotImplementedError,
            RuntimeError, ValueError) as exc:
        raise NotGradable(f"unreadable .zip archive: {type(exc).__name__}: {exc}",
                          "re-create the archive (zip -r NAME.zip FOLDER)") from exc


def extract_tar(archive: Path, dest: Path) -> None:
    """Extract a ``.tar.gz`` into ``dest`` after checking every member (tarfile's ``data`` filter too).

    Raises:
        NotGradable: unreadable archive, unsafe member (absolute, ``..``, escaping link, device), too big.
    """
    try:
        with tarfile.open(archive, "r:*") as tf:
            members = tf.getmembers()
            if len(members) > MAX_MEMBERS:
                raise NotGradable(f"the archive has {len(members)} members (at most {MAX_MEMBERS})")
            total = 0
            for member in members:
                problem = _member_ok(member.name)
                if problem:
                    raise NotGradable(f"unsafe archive member: {problem}", "re-create the archive from the workspace folder")
                if member.issym() or member.islnk():
                    link = PurePosixPath(member.linkname)
                    base = PurePosixPath(member.name).parent if member.issym() else PurePosixPath()
                    resolved = os.path.normpath(str(base / link))
                    if link.is_absolute() or resolved.startswith(".."):
                        raise NotGradable(f"unsafe archive member: link {member.name!r} points outside the archive")
                elif not (member.isfile() or member.isdir()):
                    raise NotGradable(f"unsafe archive member: {member.name!r} is a device or fifo")
                total += max(member.size, 0)
                if total > MAX_UNPACKED_BYTES:
                    raise NotGradable(f"the archive unpacks to more than {MAX_UNPACKED_BYTES} bytes")
            if hasattr(tarfile, "data_filter"):
                tf.extractall(dest, filter="data")
            else:  # pragma: no cover - Python without PEP 706; members were checked above
                tf.extractall(dest)
    except NotGradable:
        raise
    except (tarfile.TarError, OSError, EOFError, ValueError) as exc:
        raise NotGradable(f"unreadable .tar.gz archive: {type(exc).__name__}: {exc}",
                          "re-create the archive (tar czf NAME.tar.gz FOLDER)") from exc


def _has_packages(folder: Path) -> bool:
    for _root, dirs, files in os.walk(folder):
        dirs[:] = [d for d in dirs if d not in _SKIP_DIRS and d not in ("build", "install", "log")]
        if "package.xml" in files:
            return True
    return False


def _workspace_root(folder: Path) -> Path:
    """Descend through a single wrapping folder (``alice.zip`` holding ``alice/``) to the content."""
    current = folder
    for _ in range(3):
        if (current / "src").is_dir() or (current / "package.xml").is_file():
            return current
        entries = [p for p in current.iterdir() if not p.name.startswith(".") and p.name != "__MACOSX"]
        if len(entries) == 1 and entries[0].is_dir() and not entries[0].is_symlink():
            current = entries[0]
            continue
        return current
    return current


def prepare(submission: Submission, scratch: Path, packages_needed: bool = True) -> Path:
    """Copy or extract ``submission`` into ``scratch``; returns the workspace root to grade.

    ``packages_needed``: False when no lesson graded for it has packages of its own (workspace-setup, whose
    hand-in is the workspace folder itself): a folder with neither ``src/`` nor a ``package.xml`` is then
    graded as the workspace it is, as ``check`` grades it, and the lesson's checks say what it lacks (a
    workspace without ``src/`` failed workspace-setup's src_folder under ``check`` and was "not gradable"
    under ``grade``: dev validate --batch of no-src-folder).

    A ``build/`` or ``install/`` the submission holds is kept (workspace-setup grades it), but
    never trusted: the engine's build record is removed, so each lesson's packages are rebuilt
    from clean (:func:`ros2course.builder.colcon.build_packages`).

    The workspace is ``scratch/ws``: the submission's workspace as is (``src/``
    and whatever else it holds, symbolic links kept as links), or a folder of
    packages moved under ``scratch/ws/src/``.

    Raises:
        NotGradable: the entry has a problem, cannot be read, is an unsafe
            archive, or holds neither ``src/`` nor any ``package.xml`` while ``packages_needed``.
    """
    if submission.problem:
        raise NotGradable(submission.problem)
    raw = scratch / "unpacked"
    raw.mkdir(parents=True)
    path = submission.path
    name = path.name.lower()
    try:
        if path.is_dir():
            shutil.copytree(path, raw / "entry", symlinks=True,
                            ignore=shutil.ignore_patterns(*_SKIP_DIRS))
            content = raw / "entry"
        elif name.endswith(".zip"):
            extract_zip(path, raw)
            content = raw
        else:
            extract_tar(path, raw)
            content = raw
    except NotGradable:
        raise
    except (OSError, shutil.Error) as exc:
        raise NotGradable(f"cannot read the submission: {exc}") from exc
    root = _workspace_root(content)
    ws = scratch / "ws"
    if (root / "src").is_dir():
        root.rename(ws)
    elif (root / "package.xml").is_file():  # one package (the folder itself)
        (ws / "src").mkdir(parents=True)
        name = root.name if root not in (raw, raw / "entry") else student_id(submission.path.name)
        root.rename(ws / "src" / name)
    elif _has_packages(root):
        ws.mkdir()
        root.rename(ws / "src")
    elif not packages_needed:
        root.rename(ws)
    else:
        raise NotGradable("neither a workspace (no src/ folder) nor a folder of ROS packages (no package.xml)",
                          "submit your workspace folder (with src/) or your package folders")
    shutil.rmtree(raw, ignore_errors=True)
    # a hand-in is built from its own sources: the engine's record of what a build holds is never taken from
    # the submission (issue 36), so every package it brought built is rebuilt from clean before it is graded
    records = ws / "build" / RECORDS
    if records.is_file() or records.is_symlink():
        records.unlink()
    return ws
