"""ROS packages in a source folder, read from their ``package.xml`` with catkin_pkg.

catkin_pkg is the library colcon-ros itself uses to read manifests (REP 149,
format 3), so a package colcon sees is one these functions see. Used by the
build (which packages to build) and by the ROS install (which optional
components a workspace needs).

A learner's ``check`` reads the workspace's manifests several times before its
first node starts, and importing catkin_pkg (pyparsing, for its ``condition``
attributes) costs about 35 ms of that (issue 36). So what catkin_pkg reads of a
``package.xml`` is kept, keyed by the file's bytes, in ros2course's cache
folder (:func:`ros2course.files.cache_dir`, ``manifests/<sha256>.json``, this
user's own files only); catkin_pkg is imported only for a manifest not seen
before. The folder walk is catkin_pkg's ``find_package_paths`` rule, written
out here for the same reason (see :func:`package_folders`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
from pathlib import Path

from ros2course.errors import NotGradable

#: catkin_pkg's DEFAULT_IGNORE_MARKERS: a folder holding one of these is skipped, with everything below it.
IGNORE_MARKERS = frozenset({"AMENT_IGNORE", "CATKIN_IGNORE", "COLCON_IGNORE"})
MANIFEST_FILE = "package.xml"
#: Bumped when what a kept manifest holds changes.
_CACHE_FORMAT = 2
#: Kept manifests beyond this many: the oldest are removed (a class graded on this machine adds one per
#: distinct package.xml).
_CACHE_LIMIT = 4000


@dataclasses.dataclass(frozen=True)
class Dependency:
    """One dependency of a manifest (``<depend>``, ``<exec_depend>``, ...): its package name.

    Conditions (REP 149 ``condition=``) are not evaluated, as catkin_pkg's ``find_packages`` leaves them.
    """

    name: str


@dataclasses.dataclass(frozen=True)
class Export:
    """A ``<build_type>`` element of ``<export>`` (the only export the engine reads)."""

    tagname: str
    content: str


@dataclasses.dataclass(frozen=True)
class Manifest:
    """What catkin_pkg read of one ``package.xml``: the attributes of its ``Package`` the engine and graders use.

    Attributes:
        name: ``<name>``.
        version: ``<version>``.
        package_format: the ``format`` attribute of ``<package>`` (REP 149: 3; catkin_pkg reads 1 when absent).
        build_depends, buildtool_depends, exec_depends, build_export_depends, test_depends: the
            dependency lists of catkin_pkg's ``Package`` (``<depend>`` is in build, build-export and exec).
        member_of_groups: ``<member_of_group>`` entries (interface packages: ``rosidl_interface_packages``).
        exports: the ``<build_type>`` exports (tag name and text, as catkin_pkg read them).
    """

    name: str
    version: str
    package_format: int = 3
    build_depends: tuple[Dependency, ...] = ()
    buildtool_depends: tuple[Dependency, ...] = ()
    exec_depends: tuple[Dependency, ...] = ()
    build_export_depends: tuple[Dependency, ...] = ()
    test_depends: tuple[Dependency, ...] = ()
    member_of_groups: tuple[Dependency, ...] = ()
    exports: tuple[Export, ...] = ()

    def get_build_type(self) -> str:
        """catkin_pkg's ``Package.get_build_type``: the ``<build_type>``, ``catkin`` when there is none.

        Raises:
            NotGradable: more than one ``<build_type>`` (catkin_pkg's InvalidPackage).
        """
        types = [e.content for e in self.exports if e.tagname == "build_type"]
        if len(types) > 1:
            raise NotGradable(f"package {self.name}: only one <build_type> element is permitted",
                              "keep one <build_type> in package.xml's <export>")
        return types[0] if types else "catkin"

    @classmethod
    def _lists(cls) -> tuple[str, ...]:
        return tuple(f.name for f in dataclasses.fields(cls) if f.name.endswith(("depends", "groups")))

    def to_json(self) -> dict:
        """A JSON-ready dict (the cache's format)."""
        data = {"name": self.name, "version": self.version, "package_format": self.package_format,
                "exports": [[e.tagname, e.content] for e in self.exports]}
        data.update({key: [d.name for d in getattr(self, key)] for key in self._lists()})
        return data

    @classmethod
    def from_json(cls, data: dict) -> Manifest:
        """The inverse of :meth:`to_json`.

        Raises:
            KeyError, TypeError, ValueError: not a dict :meth:`to_json` made.
        """
        lists = {key: tuple(Dependency(str(n)) for n in data[key]) for key in cls._lists()}
        exports = tuple(Export(str(t), str(c)) for t, c in data["exports"])
        return cls(name=str(data["name"]), version=str(data["version"]), package_format=int(data["package_format"]),
                   exports=exports, **lists)

    @classmethod
    def from_catkin(cls, package) -> Manifest:
        """From a catkin_pkg ``Package`` (build-type exports only)."""
        lists = {key: tuple(Dependency(d.name) for d in getattr(package, key)) for key in cls._lists()}
        exports = tuple(Export(e.tagname, e.content) for e in package.exports if e.tagname == "build_type")
        return cls(name=package.name, version=package.version, package_format=int(package.package_format),
                   exports=exports, **lists)


def package_folders(src: Path) -> list[Path]:
    """Folders under ``src`` holding a ``package.xml``, sorted: catkin_pkg's ``find_package_paths`` rule.

    Symlinked folders are followed, a folder holding an ignore marker (:data:`IGNORE_MARKERS`, file or
    folder) is skipped with everything below it, hidden folders are not entered, and no folder below a
    package is searched. Written out rather than imported: ``catkin_pkg.packages`` imports its manifest
    parser and pyparsing, which a warm check must not pay for (module docstring).
    """
    found: list[Path] = []
    for folder, dirs, files in os.walk(src, followlinks=True):
        if IGNORE_MARKERS.intersection(dirs) or IGNORE_MARKERS.intersection(files):
            dirs[:] = []
            continue
        if MANIFEST_FILE in files:
            found.append(Path(folder))
            dirs[:] = []
            continue
        dirs[:] = [d for d in dirs if not d.startswith(".")]
    return sorted(found)


def _cache_path(digest: str) -> Path:
    from ros2course.files import cache_dir  # noqa: PLC0415 - platformdirs only when needed

    return cache_dir() / "manifests" / f"{digest}.json"


def _kept(digest: str) -> Manifest | None:
    """The kept manifest of these bytes, if this user wrote it; None on any doubt."""
    try:
        with open(_cache_path(digest), "rb") as handle:
            stat = os.fstat(handle.fileno())
            if stat.st_uid != os.geteuid() or stat.st_mode & 0o022:
                return None
            return Manifest.from_json(json.loads(handle.read()))
    except Exception:  # noqa: BLE001 - a missing or damaged entry only costs a parse
        return None


def _keep(digest: str, manifest: Manifest) -> None:
    """Keep ``manifest`` under ``digest``; an unwritable cache folder only costs the speed-up."""
    from ros2course.files import atomic_write_bytes  # noqa: PLC0415 - see _cache_path

    with contextlib.suppress(Exception):
        path = _cache_path(digest)
        atomic_write_bytes(path, json.dumps(manifest.to_json()).encode())
        with os.scandir(path.parent) as entries:
            kept = [e for e in entries if e.name.endswith(".json")]
        if len(kept) > _CACHE_LIMIT:
            for entry in sorted(kept, key=lambda e: e.stat().st_mtime)[:len(kept) - _CACHE_LIMIT]:
                with contextlib.suppress(OSError):
                    os.unlink(entry.path)


def _parse(data: bytes, path: Path) -> Manifest:
    """catkin_pkg's reading of ``data`` (the bytes of ``path``).

    Raises:
        NotGradable: catkin_pkg cannot parse it (its message included).
    """
    from catkin_pkg.package import InvalidPackage, parse_package_string  # noqa: PLC0415 - see the module docstring

    try:
        package = parse_package_string(data.decode("utf-8"), filename=str(path))
    # catkin_pkg raises a bare ValueError for format="3a" and an AssertionError for format="-1"
    except (InvalidPackage, ValueError, AssertionError) as exc:
        detail = " ".join(line.strip() for line in str(exc).splitlines() if line.strip())
        raise NotGradable(f"a package.xml under {path.parent} is invalid: {detail[:400]}",
                          "fix package.xml (format 3; name, version, description, maintainer with a valid email, license)") from exc
    return Manifest.from_catkin(package)


def read_manifest(path: Path) -> Manifest:
    """The manifest in ``path`` (a ``package.xml``), from the cache when these bytes were read before.

    Raises:
        NotGradable: the file cannot be read, or catkin_pkg cannot parse it.
    """
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise NotGradable(f"cannot read {path}: {exc.strerror or exc}", "check the file's permissions") from exc
    import catkin_pkg  # noqa: PLC0415 - its __init__ alone: the version, without the parser

    digest = hashlib.sha256(f"{_CACHE_FORMAT}\0{catkin_pkg.__version__}\0".encode() + data).hexdigest()
    manifest = _kept(digest)
    if manifest is None:
        manifest = _parse(data, path)
        _keep(digest, manifest)
    return manifest


def find_packages(src: Path) -> dict[str, tuple[Path, Manifest]]:
    """Every ROS package under ``src``: name -> (folder, :class:`Manifest`), as colcon finds them.

    Raises:
        NotGradable: a ``package.xml`` that catkin_pkg cannot parse (its message included), or two
            packages of one name (colcon refuses to build either).
    """
    if not src.is_dir():
        return {}
    found: dict[str, tuple[Path, Manifest]] = {}
    for folder in package_folders(src):
        manifest = read_manifest(folder / MANIFEST_FILE)
        if manifest.name in found:
            raise NotGradable(f"two packages are named {manifest.name}: {found[manifest.name][0]} and {folder}",
                              "rename or remove one of them (each <name> in src/ must be unique)")
        found[manifest.name] = (folder, manifest)
    return found


def dependency_closure(packages: list[str], found: dict[str, tuple[Path, Manifest]]) -> list[str]:
    """``packages`` plus every workspace package they depend on, recursively (sorted)."""
    todo = list(packages)
    seen: set[str] = set()
    while todo:
        name = todo.pop()
        if name in seen or name not in found:
            continue
        seen.add(name)
        pkg = found[name][1]
        for dep in (*pkg.build_depends, *pkg.buildtool_depends, *pkg.exec_depends, *pkg.build_export_depends):
            if dep.name in found:
                todo.append(dep.name)
    return sorted(seen)
