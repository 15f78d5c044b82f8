"""Courses: a folder with ``course.yaml`` beside its ``chapters/``, ``graders/`` and ``solutions/`` (issue 18).

A course is found by path (``--course PATH``) or by name: its manifest id, or the name
it registers in the ``ros2course.courses`` entry-point group, so an instructor can
publish a course as a pip package of its own. The tutorial course is bundled with the
engine (:func:`ros2course.lesson.bundled_course`). The manifest is a pydantic model, so
a malformed one is reported as ``<file>: <field>: <what is wrong>`` with a hint.
"""

from __future__ import annotations

import functools
import importlib
import importlib.metadata
from pathlib import Path
from typing import Annotated

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

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
        lessons: lesson ids in course order; each has a ``chapters/*/lesson.yaml``.
        requires: what the whole course needs installed (see ``ros2course.ros.requirements``).
    """

    model_config = ConfigDict(extra="forbid")

    id: Annotated[str, Field(pattern=_ID)]
    title: Annotated[str, Field(min_length=3)]
    version: Annotated[str, Field(pattern=r"^\d+(\.\d+)*$")]
    ros_distro: str = "jazzy"
    kit: str = "2"
    fixtures: str = "fixtures"
    lessons: list[Annotated[str, Field(pattern=_ID)]] = Field(min_length=1)
    requires: list[str] = Field(default_factory=list)


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
    """The folder of the course ``spec`` names: a path, an installed course's name, or a manifest id.

    Raises:
        CourseError: no such folder or name (the hint lists the installed courses).
    """
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
