"""Lessons: one ``chapters/<id>/lesson.yaml`` each, validated when loaded.

A :class:`Lesson` and its parts are plain dataclasses; the schema that validates
a ``lesson.yaml`` (pydantic models, so a malformed lesson is reported as
``<file>: <field>: <what is wrong>``) is :mod:`ros2course.lesson.schema`, imported
only when lessons are validated: a warm ``check`` loads the kept catalog without
pydantic or PyYAML (issue 36). The catalog's order is ``course.yaml``'s (a course's folders are
named by lesson id, so nothing else can claim an order); a folder of lessons without a
``course.yaml`` (tests, a draft) is ordered by an optional numeric ``NN-`` prefix of its folders.
"""

from __future__ import annotations

import contextlib
import dataclasses
import difflib
import functools
import hashlib
import os
import pickle
import re
import sys
from pathlib import Path

from ros2course.errors import LessonFormatError, UnknownLesson
from ros2course.lesson import MANIFEST, Course, active_course, content_root  # noqa: F401 - content_root re-exported: callers import it from here



@dataclasses.dataclass
class ReferenceSolution:
    """How ``dev validate`` prepares the reference workspace for this lesson."""

    #: Shell commands run in the workspace before grading (what the learner types).
    commands: list[str] = dataclasses.field(default_factory=list)


@dataclasses.dataclass
class GraphNode:
    """A node the lesson's contract expects in the graph (``ros2 node list``).

    Attributes:
        name: fully qualified, e.g. ``/amazing_quote_publisher_node``.
        part: the grader's part (:attr:`ros2course.grade.checklist.Check.part`) whose graph holds it; "" for every part.
    """

    name: str
    part: str = ""


@dataclasses.dataclass
class GraphEndpoint:
    """A topic or service end the learner's node is expected to have (``ros2 topic info -v``,
    ``ros2 service list -t``).

    Attributes:
        name: fully qualified topic or service name.
        type: its interface type, ``pkg/msg/Name`` (topics) or ``pkg/srv/Name`` (services).
        role: ``publish`` / ``subscribe`` (topics: the learner's node publishes and the grader listens,
            or the reverse) or ``serve`` / ``call`` (services: the learner's node is the server or
            its client); default the first of its list's roles (:class:`LessonGraph` fills it in).
        part: as :attr:`GraphNode.part`.
    """

    name: str
    type: str
    role: str = ""
    part: str = ""


@dataclasses.dataclass
class LessonGraph:
    """The graph a lesson's contract expects while its learner nodes run (``graph:`` in lesson.yaml).

    Optional. When a check that watched the graph fails, the engine compares
    these entries with what the graph shows then and attaches a diagnosis
    (:mod:`ros2course.run.diagnose`); it never changes a verdict.
    """

    nodes: list[GraphNode] = dataclasses.field(default_factory=list)
    topics: list[GraphEndpoint] = dataclasses.field(default_factory=list)
    services: list[GraphEndpoint] = dataclasses.field(default_factory=list)

    @classmethod
    def validate(cls, data: dict) -> LessonGraph:
        """A ``graph:`` mapping validated (:func:`ros2course.lesson.schema.validate_graph`).

        Raises:
            pydantic.ValidationError: a schema violation.
        """
        from ros2course.lesson.schema import validate_graph  # noqa: PLC0415 - pydantic only to validate

        return cls.from_values(validate_graph(data))

    @classmethod
    def from_values(cls, values: dict) -> LessonGraph:
        """From validated plain values (:func:`ros2course.lesson.schema.validate_graph`)."""
        return cls(nodes=[GraphNode(**n) for n in values["nodes"]],
                   topics=[GraphEndpoint(**e) for e in values["topics"]],
                   services=[GraphEndpoint(**e) for e in values["services"]])

    def for_part(self, part: str) -> LessonGraph:
        """The entries that apply to a check of grader part ``part`` (its own and the part-less ones)."""
        def keep(entries: list) -> list:
            return [e for e in entries if e.part in ("", part)]

        return LessonGraph(nodes=keep(self.nodes), topics=keep(self.topics), services=keep(self.services))


@dataclasses.dataclass
class Lesson:
    """One graded exercise, as declared in its ``lesson.yaml``.

    Attributes:
        id: stable lesson id from shared/LESSONS.md (kebab-case).
        title: one line.
        beyond: for a lesson the seed tutorial has no chapter for (it was written for Humble and
            teaches no QoS or managed nodes: issue 20), where its subject is documented.
        chapters: seed tutorial chapter numbers this lesson follows; empty only with ``beyond``.
        requires: what must be installed (see ``ros2course.ros.env.KNOWN_REQUIREMENTS``).
        packages: ROS packages ``check`` builds with colcon (``--packages-up-to``).
        instructions: markdown shown by ``next``.
        hints: ordered from gentle to nearly the answer; ``hint`` shows them one at a time.
        grader: module name under ``graders/`` exposing ``CHECKS`` and ``grade``.
        starter: folder (relative to the lesson folder) copied into the workspace by ``next``.
        starter_includes: ids of earlier lessons whose starter files this lesson offers too
            (e.g. launch-files builds on the parameters package); its own ``starter``
            files win where both have the same path.
        reference: how ``dev validate`` readies the reference solution.
        starter_solutions: finished work offered with the starter, as ``src/<package>`` folders or
            files of ``solutions/``: an earlier lesson's package (the publisher lesson offers lesson
            16's interfaces to a learner who skipped it) or a module the lesson gives whole (sas's
            ``sas_lite.py``). Like every starter file, a learner's own version is kept. Below
            ``starter_includes`` and ``starter`` where paths overlap.
        interfaces: interface packages whose generated types the grader itself imports
            (:meth:`ros2course.grade.session.GradingSession.interface_type` refuses any other). Batch
            grading builds them once from ``solutions/`` and imports that trusted build, never
            the submission's, even when the lesson teaches the package itself.
        references: reference packages of ``solutions/src`` whose sources the grader itself reads
            (:meth:`ros2course.grade.session.GradingSession.reference_package` refuses any other): the
            code a testing lesson runs the learner's tests against. Batch grading copies them with
            its trusted build, since ``solutions/`` is hidden from the sandbox.
        folders: workspace folders holding the lesson's files outside any ROS package
            (the preamble's ``python/minimalist_package``); ``dev validate`` copies them
            from ``solutions/`` for the reference and its wrong solutions.
        graph: the nodes, topics and services the contract expects in the graph (:class:`LessonGraph`),
            or None; the engine diagnoses failed checks against it.
    """

    id: str
    title: str
    instructions: str
    hints: list[str]
    grader: str
    beyond: str = ""
    chapters: list[int] = dataclasses.field(default_factory=list)
    requires: list[str] = dataclasses.field(default_factory=list)
    packages: list[str] = dataclasses.field(default_factory=list)
    starter: str = "starter"
    starter_includes: list[str] = dataclasses.field(default_factory=list)
    reference: ReferenceSolution = dataclasses.field(default_factory=ReferenceSolution)
    interfaces: list[str] = dataclasses.field(default_factory=list)
    references: list[str] = dataclasses.field(default_factory=list)
    folders: list[str] = dataclasses.field(default_factory=list)
    starter_solutions: list[str] = dataclasses.field(default_factory=list)
    graph: LessonGraph | None = None

    #: The lesson's folder; set by the loader, not read from YAML.
    folder: Path = Path(".")
    #: The course the lesson belongs to (its graders, solutions and other lessons); set by the loader: the
    #: folder holding ``chapters/<lesson folder>`` (a lesson made in code belongs to the command's course).
    course: Course = dataclasses.field(default_factory=active_course)
    #: Starter folders of ``starter_includes`` (oldest first); set by :class:`Catalog`.
    included_starters: list[Path] = dataclasses.field(default_factory=list)

    @property
    def starter_dir(self) -> Path:
        """Absolute path of the starter folder (may not exist for lessons without files)."""
        return self.folder / self.starter

    @property
    def workspace_paths(self) -> list[str]:
        """Where the lesson's files live in a workspace, relative to its root.

        ``src/<package>`` for each ROS package, then each of ``folders``; a
        lesson with neither names its starter's top-level entries
        (terminal-basics: ``terminal_basics``).
        """
        paths = [f"src/{name}" for name in self.packages] + list(self.folders)
        if not paths and self.starter_dir.is_dir():
            paths = sorted(entry.name for entry in self.starter_dir.iterdir())
        return paths

    @property
    def starter_layers(self) -> list[Path]:
        """Starter folders in the order they are laid down: included lessons' first, this lesson's last."""
        return [*self.included_starters, self.starter_dir]


def yaml_error_text(exc: Exception) -> str:
    """PyYAML's error on one line: ``line L, column C: problem (context)``."""
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    context = getattr(exc, "context", None)
    where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
    return f"{where}{problem}" + (f" ({context})" if context else "")


def load_lesson(path: Path) -> Lesson:
    """Load and validate one ``lesson.yaml``.

    Raises:
        LessonFormatError: unreadable YAML or a schema violation, naming file and field.
    """
    import yaml  # noqa: PLC0415 - only when lessons are validated (the kept catalog needs neither yaml nor pydantic)
    from pydantic import ValidationError  # noqa: PLC0415 - same

    from ros2course.lesson.schema import format_validation_error, validate_lesson  # noqa: PLC0415 - same

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml's where PyYAML has it (10x faster)
    try:
        data = yaml.load(path.read_text(encoding="utf-8"), Loader=loader)  # noqa: S506 - a safe loader
    except OSError as exc:
        raise LessonFormatError(f"{path}: cannot be read: {exc.strerror}", "check the file exists and is readable") from exc
    except yaml.YAMLError as exc:
        raise LessonFormatError(f"{path}: not valid YAML: {yaml_error_text(exc)}",
                                "fix the YAML syntax (indentation, quotes)") from exc
    if not isinstance(data, dict):
        raise LessonFormatError(f"{path}: (top level): expected a mapping of fields, got {type(data).__name__}",
                                "a lesson file is a YAML mapping with id, title, instructions, hints, grader")
    try:
        values = validate_lesson(data)
    except ValidationError as exc:
        raise LessonFormatError(format_validation_error(path, exc),
                                "see course/lesson/schema.py (LessonSchema) for the lesson schema") from exc
    values["reference"] = ReferenceSolution(**values["reference"])
    values["graph"] = None if values["graph"] is None else LessonGraph.from_values(values["graph"])
    lesson = Lesson(**values)
    lesson.folder = path.parent
    lesson.course = Course(path.parent.parent.parent)
    folder_id = re.sub(r"^\d+-", "", path.parent.name)
    if folder_id != lesson.id:
        raise LessonFormatError(f"{path}: id: {lesson.id!r} does not match its folder name {path.parent.name!r}",
                                "name the folder after the lesson id (NN-<id> only in a folder without course.yaml)")
    return lesson


class Catalog:
    """Every lesson of the course, in order.

    Args:
        chapters_dir: folder of ``<id>/lesson.yaml`` folders (``NN-<id>`` without a ``course.yaml``).
    """

    def __init__(self, chapters_dir: Path) -> None:
        self.chapters_dir = chapters_dir
        #: the course these lessons belong to (every lesson's :attr:`Lesson.course`)
        self.course = Course(chapters_dir.parent)
        if not chapters_dir.is_dir():
            raise LessonFormatError(f"no chapters folder at {chapters_dir}", "give the course folder with --course PATH")
        folders = sorted((p for p in chapters_dir.iterdir() if (p / "lesson.yaml").is_file()),
                         key=lambda p: (int(m.group(1)) if (m := re.match(r"^(\d+)-", p.name)) else 10**6, p.name))
        self.lessons: list[Lesson] = [load_lesson(p / "lesson.yaml") for p in folders]
        seen: set[str] = set()
        for lesson in self.lessons:
            if lesson.id in seen:
                raise LessonFormatError(f"{lesson.folder}: id: duplicate lesson id {lesson.id!r}", "ids must be unique")
            seen.add(lesson.id)
        if (chapters_dir.parent / MANIFEST).is_file():
            self.lessons = self._in_manifest_order(chapters_dir.parent)
        self._resolve_starter_includes()

    def _in_manifest_order(self, course_root: Path) -> list[Lesson]:
        """The lessons in the order ``course.yaml`` lists them.

        Raises:
            LessonFormatError: the manifest names a lesson no chapter folder holds, or a
                chapter folder holds a lesson the manifest does not list.
        """
        from ros2course.lesson.courses import load_manifest  # noqa: PLC0415 - pydantic is loaded here anyway

        manifest = load_manifest(course_root)
        by_id = {lesson.id: lesson for lesson in self.lessons}
        path = course_root / MANIFEST
        for lesson_id in manifest.lessons:
            if lesson_id not in by_id:
                close = difflib.get_close_matches(lesson_id, list(by_id), n=1)
                raise LessonFormatError(f"{path}: lessons: {lesson_id!r} has no chapters/*/lesson.yaml",
                                        f"did you mean {close[0]}?" if close else "add the lesson's folder or remove the id")
        unlisted = [lesson for lesson in self.lessons if lesson.id not in manifest.lessons]
        if unlisted:
            raise LessonFormatError(f"{path}: lessons: {unlisted[0].id!r} ({unlisted[0].folder.name}) is not listed",
                                    "add it to course.yaml's lessons where it belongs in the course")
        return [by_id[lesson_id] for lesson_id in manifest.lessons]

    def _resolve_starter_includes(self) -> None:
        """Set each lesson's ``included_starters`` from its ``starter_includes`` (earlier lessons only).

        Raises:
            LessonFormatError: an include names no lesson, or a lesson that does not come earlier.
        """
        by_id = {lesson.id: lesson for lesson in self.lessons}
        for index, lesson in enumerate(self.lessons):
            earlier = {other.id for other in self.lessons[:index]}
            layers: list[Path] = []
            for included in lesson.starter_includes:
                if included not in earlier:
                    problem = "no such lesson" if included not in by_id else "it does not come earlier in the course"
                    raise LessonFormatError(f"{lesson.folder / 'lesson.yaml'}: starter_includes: {included!r}: "
                                            f"{problem}", "name lessons that come before this one")
                # earlier lessons are resolved already, so their own includes come with them
                layers += [p for p in by_id[included].starter_layers if p not in layers]
            lesson.included_starters = layers

    def get(self, lesson_id: str) -> Lesson:
        """The lesson with this id.

        Raises:
            UnknownLesson: with the closest ids as a hint.
        """
        for lesson in self.lessons:
            if lesson.id == lesson_id:
                return lesson

        close = difflib.get_close_matches(lesson_id, self.ids(), n=3)
        hint = f"did you mean {', '.join(close)}?" if close else "run 'ros2course list' to see every lesson id"
        raise UnknownLesson(f"unknown lesson {lesson_id!r}", hint)

    def ids(self) -> list[str]:
        """Lesson ids in course order."""
        return [lesson.id for lesson in self.lessons]

    def after(self, lesson_id: str | None) -> Lesson | None:
        """The lesson following ``lesson_id`` (the first one for None), or None at the end."""
        ids = self.ids()
        if lesson_id is None:
            return self.lessons[0] if self.lessons else None
        index = ids.index(lesson_id)
        return self.lessons[index + 1] if index + 1 < len(ids) else None


def load_catalog(root: Path | None = None) -> Catalog:
    """The catalog under ``root/chapters`` (default: the active course, :func:`content_root`), cached per folder."""
    return _catalog_of(root or content_root())


@functools.lru_cache(maxsize=4)
def _catalog_of(root: Path) -> Catalog:
    chapters_dir = root / "chapters"
    key = _catalog_key(chapters_dir)
    cached = _cached_catalog(chapters_dir, key) if key is not None else None
    if cached is not None:
        return cached
    catalog = Catalog(chapters_dir)
    if key is not None:
        _save_catalog(chapters_dir, key, catalog)
    return catalog


# --- the validated catalog, kept between processes ------------------------------------------------
#
# Every `check` loads the catalog before it starts the learner's nodes; validating 34 lesson.yaml files
# imports PyYAML and pydantic and builds pydantic's schemas (~100 ms of the CLI's start, issue 36). The
# validated Catalog (plain dataclasses) is kept in the user's cache folder, keyed by the *contents* of
# everything validation reads (never by file times: a course copied with old times must not be graded on a
# stale lesson), and loaded without validation. pickle rather than JSON: the lessons hold Path fields and
# nested values that JSON would need a second schema for. A cache file is trusted only when this user
# owns it and no one else may write it (like ssh's own files); anything else, or any error, means a full load.

#: Bumped when what the cache holds changes.
_CACHE_FORMAT = 3


def _catalog_key(chapters_dir: Path) -> str | None:
    """sha256 (hex) of what a full load reads: every ``lesson.yaml``, ``course.yaml``, the loader's code and
    versions; None when the folder cannot be read (the full load then reports why)."""
    digest = hashlib.sha256(f"{_CACHE_FORMAT}\0{sys.version}\0{chapters_dir}\n".encode())
    here = Path(__file__).resolve().parent
    try:
        for code in (here / "catalog.py", here / "schema.py", here / "courses.py", here.parent / "ros" / "requirements.py",
                     _pydantic_version_file()):
            digest.update(code.read_bytes())
        with os.scandir(chapters_dir) as entries:
            names = sorted(entry.name for entry in entries)
        for name in names:
            with contextlib.suppress(FileNotFoundError, NotADirectoryError):
                data = (chapters_dir / name / "lesson.yaml").read_bytes()
                digest.update(f"\0{name}\0{len(data)}\0".encode() + data)
        with contextlib.suppress(FileNotFoundError):
            digest.update(b"\0manifest\0" + (chapters_dir.parent / MANIFEST).read_bytes())
    except OSError:
        return None
    return digest.hexdigest()


def _pydantic_version_file() -> Path:
    """pydantic's ``version.py`` (its VERSION), found without importing pydantic (the validation it does is
    part of what the kept catalog holds).

    Raises:
        OSError: pydantic is not installed where the import system would find it.
    """
    import importlib.util  # noqa: PLC0415 - imported by the interpreter's start already

    spec = importlib.util.find_spec("pydantic")
    if spec is None or spec.origin is None:
        raise OSError("pydantic is not installed")
    return Path(spec.origin).with_name("version.py")


def _catalog_cache_path(chapters_dir: Path) -> Path:
    from ros2course.files import cache_dir  # noqa: PLC0415 - platformdirs only when needed

    return cache_dir() / f"catalog-{hashlib.sha256(str(chapters_dir).encode()).hexdigest()[:16]}.pickle"


def _cached_catalog(chapters_dir: Path, key: str) -> Catalog | None:
    """The kept catalog when its key is ``key`` and the file is this user's own, else None."""
    try:
        with open(_catalog_cache_path(chapters_dir), "rb") as handle:
            stat = os.fstat(handle.fileno())
            if stat.st_uid != os.geteuid() or stat.st_mode & 0o022:
                return None
            data = pickle.load(handle)  # noqa: S301 - this user's own file, see the comment above
    except Exception:  # noqa: BLE001 - a missing, damaged or outdated cache only costs the full load
        return None
    if not isinstance(data, dict) or data.get("key") != key or not isinstance(data.get("catalog"), Catalog):
        return None
    return data["catalog"]


def _save_catalog(chapters_dir: Path, key: str, catalog: Catalog) -> None:
    """Keep ``catalog`` (validated) under ``key``; an unwritable cache folder only costs the speed-up."""
    from ros2course.files import atomic_write_bytes  # noqa: PLC0415 - see _catalog_cache_path

    with contextlib.suppress(Exception):
        path = _catalog_cache_path(chapters_dir)
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(path, pickle.dumps({"key": key, "catalog": catalog}, protocol=pickle.HIGHEST_PROTOCOL))
