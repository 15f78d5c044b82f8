"""Courses: a folder with ``course.yaml`` beside its ``chapters/``, ``graders/`` and ``solutions/`` (issue 18).

A course is found by path (``--course PATH``) or by name: its manifest id, or the name
it registers in the ``ros2course.courses`` entry-point group, so an instructor can
publish a course as a pip package of its own. The tutorial course is bundled with the
engine (:func:`ros2course.lesson.bundled_course`). The manifest is a pydantic model, so
a malformed one is reported as ``<file>: <field>: <what is wrong>`` with a hint.
"""

from __future__ import annotations

import atexit
import contextlib
import functools
import hashlib
import importlib
import importlib.metadata
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Annotated

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from ros2course.errors import CourseError, LessonFormatError
# bundled_course is imported here on purpose: pyproject's entry point ros2course.courses names
# ros2course.lesson.courses:bundled_course (the bundled tutorial course registers itself like any other)
from ros2course.lesson import ID_PATTERN as _ID, MANIFEST, bundled_course  # noqa: F401

#: the entry-point group a course package registers its folder in
ENTRY_POINT_GROUP = "ros2course.courses"


class CourseManifest(BaseModel):
    """A course's ``course.yaml``.

    Attributes:
        id: stable kebab-case id, recorded in every workspace that follows the course.
        title: one line.
        version: the course's version (a workspace records it; ``--version`` prints it).
        ros_distro: the ROS 2 distribution the lessons are written for (``jazzy``).
        kit: the major version of the engine's grading API (:data:`ros2course.kit.API_VERSION`)
            the graders are written for; the engine refuses a course written for another.
        fixtures: folder of wrong solutions (``<fixtures>/<lesson-id>/<case>``), relative to the course.
        lessons: lesson ids in course order; each has a ``chapters/*/lesson.yaml``. A course that
            ``extends`` another may leave it out (the other's lessons, in its order).
        requires: what the whole course needs installed (see ``ros2course.ros.requirements``).
        extends: another course (a path relative to this folder, an installed course's name or a manifest id)
            this one adds to: an instructor's private course holding only what learners must not see, such
            as graders with hidden checks (issue 39). Its files replace the other's at the same paths; the
            other's graders stay importable as ``graders/parent/`` (:func:`course_folder`).
    """

    model_config = ConfigDict(extra="forbid")

    id: Annotated[str, Field(pattern=_ID)]
    title: Annotated[str, Field(min_length=3)]
    version: Annotated[str, Field(pattern=r"^\d+(\.\d+)*$")]
    ros_distro: str = "jazzy"
    kit: str = "2"
    fixtures: str = "fixtures"
    lessons: list[Annotated[str, Field(pattern=_ID)]] = Field(default_factory=list)
    requires: list[str] = Field(default_factory=list)
    extends: str | None = None

    @model_validator(mode="after")
    def _lessons_unless_extending(self) -> CourseManifest:
        if not self.lessons and self.extends is None:
            raise ValueError("lessons: a course lists at least one lesson id (or extends another course)")
        return self


@functools.lru_cache(maxsize=8)
def load_manifest(root: Path) -> CourseManifest:
    """Read and validate ``root/course.yaml``.

    Args:
        root: the course folder.

    Raises:
        LessonFormatError: no manifest, invalid YAML, or a field that breaks the schema
            (``<file>: <field>: <problem>``, with a hint); a course for another kit version.
    """
    path = root / MANIFEST
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except FileNotFoundError as exc:
        raise LessonFormatError(f"{root} is not a course folder: no {MANIFEST}",
                                "a course folder holds course.yaml, chapters/, graders/ and solutions/") from exc
    except (OSError, yaml.YAMLError) as exc:
        raise LessonFormatError(f"{path}: not valid YAML ({str(exc).splitlines()[0]})",
                                "fix the file's syntax (indentation, quotes)") from exc
    if not isinstance(data, dict):
        raise LessonFormatError(f"{path}: expected a mapping of fields", "see the tutorial course's course.yaml")
    try:
        manifest = CourseManifest.model_validate(data)
    except ValidationError as exc:
        first = exc.errors()[0]
        field = ".".join(str(part) for part in first["loc"]) or "(top level)"
        raise LessonFormatError(f"{path}: {field}: {first['msg']}",
                                "see the fields documented in ros2course.lesson.courses.CourseManifest") from exc
    from ros2course.kit_version import API_VERSION  # noqa: PLC0415 - a constant, no kit import at list time

    if manifest.kit.split(".")[0] != API_VERSION.split(".")[0]:
        raise LessonFormatError(f"{path}: kit: the course is written for grading API {manifest.kit}, "
                                f"this ros2course provides {API_VERSION}",
                                "install the ros2course version the course names, or update the course's graders")
    return manifest


def installed_courses() -> dict[str, importlib.metadata.EntryPoint]:
    """The courses registered in the ``ros2course.courses`` entry-point group, by name."""
    return {entry.name: entry for entry in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP)}


def entry_point_folder(entry: importlib.metadata.EntryPoint) -> Path:
    """The folder a course entry point names: ``module:function`` returning it, or a module whose folder it is.

    Raises:
        CourseError: the entry point's package cannot be imported (e.g. uninstalled).
    """
    try:
        target = entry.load()
    except Exception as exc:  # noqa: BLE001 - any import failure of another package: name it
        raise CourseError(f"course {entry.name!r} ({entry.value}) cannot be loaded: {exc}",
                          f"reinstall the package that provides it ({entry.dist.name if entry.dist else 'unknown'})") from exc
    if callable(target):
        return Path(target()).resolve()
    return Path(target.__file__).resolve().parent


def find_course(spec: str) -> Path:
    """The folder of the course ``spec`` names: a path, an installed course's name, or a manifest id; for a
    course that ``extends`` another, the folder of the two merged (:func:`course_folder`).

    Raises:
        CourseError: no such folder or name (the hint lists the installed courses); a course it extends
            cannot be found, or extends itself.
        LessonFormatError: a malformed course.yaml.
    """
    return course_folder(_locate(spec))


def _locate(spec: str) -> Path:
    """:func:`find_course`'s folder before any merge (see there; raises the same)."""
    path = Path(spec).expanduser()
    if path.exists() or "/" in spec or spec.startswith("."):
        if not (path / MANIFEST).is_file():
            raise CourseError(f"no course at {path} (no {MANIFEST} there)",
                              "give the folder that holds course.yaml, chapters/ and graders/")
        return path.resolve()
    entries = installed_courses()
    if spec in entries:
        return entry_point_folder(entries[spec])
    for entry in entries.values():
        try:
            folder = entry_point_folder(entry)
            if load_manifest(folder).id == spec:
                return folder
        except (CourseError, LessonFormatError):
            continue
    names = ", ".join(sorted(entries)) or "none"
    raise CourseError(f"no course named {spec!r} is installed (installed: {names})",
                      "pip install the course's package, or give its folder: --course PATH")


def course_fixtures(root: Path) -> Path:
    """The course's folder of wrong solutions (``course.yaml``'s ``fixtures``; ``tests/fixtures`` without a manifest).

    Raises:
        LessonFormatError: the manifest is malformed.
    """
    if not (root / MANIFEST).is_file():
        return root / "tests" / "fixtures"
    return root / load_manifest(root).fixtures


#: Inside a merged course, the folder (under ``graders/``) holding the extended course's graders unchanged.
PARENT_GRADERS = "parent"
#: Never copied into a merged course: caches and version control.
_NOT_COURSE = shutil.ignore_patterns("__pycache__", "*.pyc", ".git", ".pytest_cache", ".ruff_cache")


def course_folder(root: Path, _seen: tuple[Path, ...] = ()) -> Path:
    """``root`` itself, or, when its course.yaml ``extends`` another course, one folder holding both.

    The merged folder is a whole course, so every part of the engine (catalog, graders, solutions,
    fixtures, a batch worker told its course by path) reads it as it reads any other: the extended
    course's files, then this course's files at the same relative paths in their place (course.yaml
    aside), and the extended course's ``graders/`` again under ``graders/parent/``, so a private grader
    can add hidden checks to the public one it replaces::

        from .parent.print_forever_node import CHECKS as PUBLIC, grade as grade_public
        CHECKS = [*PUBLIC, Check("no_busy_wait", "...", 1, visibility="hidden")]

    Its course.yaml is the extended one's with this one's ``id``, ``title``, ``version``, ``lessons``
    (when given) and ``requires`` (added). It is made once per content (a hash of every file of both) in a
    folder every user can read (a batch's sandboxed worker reads it): ``<sys.prefix>/var/cache/ros2course/
    courses``, or a temporary folder removed at exit when that cannot be written. Why not a search path of
    course folders: a :class:`ros2course.lesson.Course` is one folder (its graders, chapters and solutions side
    by side, carried by every lesson), and one folder keeps them all right; an instructor sees exactly what was
    graded.

    Raises:
        CourseError: the extended course is not found, or the chain comes back to a course already in it.
        LessonFormatError: a malformed course.yaml on the way.
    """
    manifest = load_manifest(root)
    if manifest.extends is None:
        return root
    if root in _seen:
        raise CourseError(f"{root / MANIFEST}: extends: the courses extend each other in a loop",
                          "a private course extends the public course, which extends nothing")
    spec = manifest.extends
    try:  # a path is relative to this course's folder; a name or id is looked up as --course looks it up
        parent = course_folder(_locate(str(root / spec) if "/" in spec or spec.startswith(".") else spec).resolve(),
                               (*_seen, root))
    except CourseError as exc:
        raise CourseError(f"{root / MANIFEST}: extends: {exc.message}", exc.hint) from exc
    parent_manifest = load_manifest(parent)
    parts = [*_parts(parent, parent_manifest, parent_manifest.fixtures), *_parts(root, manifest, parent_manifest.fixtures)]
    digest = hashlib.sha256(f"{_MERGE_FORMAT}\0{root}\0{parent}\0".encode())
    for source, rel in parts:
        digest.update(f"{rel}\0".encode() + _tree_digest(source))
    key = digest.hexdigest()[:24]
    cache = _merged_cache()
    target = cache / key
    if (target / MANIFEST).is_file():
        with contextlib.suppress(OSError):
            os.utime(target / MANIFEST)  # in use: kept by _prune_merged
        return target
    _prune_merged(cache)
    staging = Path(tempfile.mkdtemp(prefix=f".{key}-", dir=cache))
    try:
        merged = staging / "course"
        merged.mkdir()
        if (parent / "graders").is_dir():
            shutil.copytree(parent / "graders", merged / "graders" / PARENT_GRADERS, ignore=_NOT_COURSE)
        for source, rel in parts:  # the extended course's parts, then this one's over them
            shutil.copytree(source, merged / rel, ignore=_NOT_COURSE, dirs_exist_ok=True)
        _write_merged_manifest(merged / MANIFEST, parent_manifest, manifest)
        sources = [root, *(course_sources(parent) or [parent])]  # raw folders, never a merged one
        (merged / SOURCES_FILE).write_text("".join(f"{folder}\n" for folder in sources), encoding="utf-8")
        for folder, _dirs, files in os.walk(merged):  # every user reads it: a batch's worker runs as another uid
            os.chmod(folder, 0o755)
            for name in files:
                os.chmod(os.path.join(folder, name), 0o644)
        try:
            os.rename(merged, target)
        except OSError:  # another process made it meanwhile: the same content
            if not (target / MANIFEST).is_file():
                raise
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return target


#: The folders of a course (setup.py's COURSE_PARTS, course.yaml and the fixtures aside): a source checkout's
#: course folder is the whole repository, and only these are the course.
COURSE_FOLDERS = ("chapters", "graders", "solutions", "gradescope")


def _parts(root: Path, manifest: CourseManifest, fixtures_to: str) -> list[tuple[Path, str]]:
    """``(folder, path in the merged course)`` of each course folder ``root`` has; its fixtures go to ``fixtures_to``."""
    parts = [(root / name, name) for name in COURSE_FOLDERS] + [(root / manifest.fixtures, fixtures_to)]
    return [(folder, rel) for folder, rel in parts if folder.is_dir()]


def _tree_digest(root: Path) -> bytes:
    """sha256 over every file's path and bytes under ``root`` (caches left out)."""
    digest = hashlib.sha256()
    for folder, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if not _NOT_COURSE(folder, [d]))
        for name in sorted(files):
            if _NOT_COURSE(folder, [name]):
                continue
            path = Path(folder) / name
            digest.update(f"{path.relative_to(root)}\0".encode())
            digest.update(hashlib.sha256(path.read_bytes()).digest())
    return digest.digest()


#: What a merged course holds, by version: a merged folder made by another version of this code is made again.
_MERGE_FORMAT = "2"
#: In a merged course: the folders it was made from, one per line, the private course first.
SOURCES_FILE = ".ros2course-sources"


def course_sources(root: Path) -> list[Path]:
    """The course folders a merged course (:func:`course_folder`) was made from, the extending one first; [] for
    a course that extends nothing. Batch grading hides them from submissions (their solutions, fixtures, and
    the private course whole), as it hides the merged course's own solutions and fixtures."""
    try:
        return [Path(line) for line in (root / SOURCES_FILE).read_text(encoding="utf-8").splitlines() if line]
    except OSError:
        return []


#: A merged course unused for this long is deleted when another is made, seconds (the reference builds' rule).
MERGED_MAX_AGE = 14 * 24 * 3600.0


def _prune_merged(cache: Path) -> None:
    """Delete the merged courses of ``cache`` unused for :data:`MERGED_MAX_AGE` (a private course edited
    many times leaves one per content)."""
    now = time.time()
    for manifest in cache.glob(f"*/{MANIFEST}"):
        with contextlib.suppress(OSError):
            if now - manifest.stat().st_mtime > MERGED_MAX_AGE:
                shutil.rmtree(manifest.parent, ignore_errors=True)


def _merged_cache() -> Path:
    """Where merged courses are kept: beside the ROS install (:func:`ros2course.builder.reference.reference_cache_root`'s
    rules: ours, not writable by others), else a temporary folder removed when this process ends."""
    root = Path(sys.prefix) / "var" / "cache" / "ros2course" / "courses"
    try:
        root.mkdir(parents=True, exist_ok=True)
        st = root.stat()
        if os.access(root, os.W_OK) and st.st_uid == os.geteuid() and not st.st_mode & 0o022:
            return root
    except OSError:
        pass
    folder = Path(tempfile.mkdtemp(prefix="ros2course-courses-"))
    folder.chmod(0o755)
    atexit.register(shutil.rmtree, folder, True)
    return folder


def _write_merged_manifest(path: Path, parent: CourseManifest, child: CourseManifest) -> None:
    data = parent.model_dump(exclude_none=True)
    data.update(id=child.id, title=child.title, version=child.version,
                lessons=child.lessons or parent.lessons,
                requires=list(dict.fromkeys([*parent.requires, *child.requires])))
    data.pop("extends", None)
    path.write_text(f"# merged by ros2course: {child.id} (extends {parent.id})\n"
                    + yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
