"""Mutation analysis of a lesson's grader (issue 24): mutants of the reference, triage, score.

A *mutant* is the lesson's reference workspace with one of its files replaced by
a copy carrying one small change, made by a maintained mutation tool,
`universalmutator <https://github.com/agroce/universalmutator>`_ (regular-expression
rules: its Python rules with its own trivial-compiler-equivalence check for
``.py`` files, which drops mutants that do not compile or compile to the same
bytecode; its C/C++ rules for C and C++ sources; its universal rules for
scripts, CMake, package.xml and anything else). This module never invents a
mutation of its own.

Each mutant is graded by the lesson's grader (through the batch engine,
:mod:`ros2course.batch.mutate`) and classified (:func:`classify`):

* ``killed``: graded, lost points (the checks it lost are named);
* ``killed by build``: the workspace does not build, so no check ran (C++ mutants that do not
  compile, a CMakeLists.txt or setup.cfg colcon cannot use; a package.xml that is not XML is never
  generated: :func:`invalid_mutant`);
* ``survived``: full marks: the grader did not notice the change;
* ``timed out`` / ``grader error``: neither (reported, never counted as killed).

``chapters/<lesson>/mutation.yaml``, beside ``lesson.yaml``, is the author's
triage of survivors judged equivalent or outside the lesson's contract::

    # optional: which reference files are mutated (globs, workspace-relative);
    # default: the lesson's own files (:func:`lesson_files`)
    files: [src/python_package_with_a_node/python_package_with_a_node/print_forever_node.py]
    survivors:
      - file: src/python_package_with_a_node/python_package_with_a_node/print_forever_node.py
        line: "def main(args=None):"          # the original line (stripped)
        mutant: "def main(args=None):  pass"  # the mutated line (stripped); or `key: <mutant key>`
        reason: "..."
      - file: src/python_package_with_a_node/package.xml
        line: "<description>Prints forever</description>"
        every_mutant: true                    # any change of this line (free text no program reads)
        reason: "..."

Score = killed / (generated - killed by build - triaged), over the graded mutants
(a sample when ``--sample`` is given). An entry matching no current mutant is *stale*.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import difflib
import fnmatch
import hashlib
import importlib.util
import json
import random
import re
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET  # noqa: N817 - the standard alias
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator
from ros2course.errors import CourseError, LessonFormatError, MissingRequirement
from ros2course.files import atomic_write_text
from ros2course.grade.results import LessonResult, Status
from ros2course.lesson.catalog import (
    Lesson,
    content_root,
    format_validation_error,
    load_catalog,
    yaml_error_text,
)
from ros2course.lesson.courses import MANIFEST, load_manifest

#: Name of the triage file beside ``lesson.yaml``.
TRIAGE_FILE = "mutation.yaml"
#: The lesson's last mutation score, beside ``lesson.yaml``: written by ``dev mutate``, shown by ``dev validate``.
SCORE_FILE = "mutation-score.json"
#: Every graded mutant's outcome of the lesson's last run, beside its score (:func:`write_score`).
OUTCOMES_FILE = "mutation-outcomes.json"
#: The outcomes of a mutant, in the order the table shows them.
KILLED, KILLED_BY_BUILD, SURVIVED, TIMED_OUT, GRADER_ERROR = (
    "killed", "killed by build", "survived", "timed out", "grader error")
OUTCOMES = (KILLED, KILLED_BY_BUILD, SURVIVED, TIMED_OUT, GRADER_ERROR)
#: universalmutator's language per file suffix; other files get its universal rules only.
LANGUAGES = {".py": "python", ".c": "c", ".h": "c", ".cpp": "cpp", ".cc": "cpp", ".hpp": "cpp"}
#: Languages whose mutants universalmutator itself checks (compiles, drops invalid and duplicate ones).
#: C/C++ cannot be compiled alone (ROS headers): their broken mutants are counted as killed by build.
CHECKED_LANGUAGES = {"python"}
#: Files never mutated: generated, binary or bookkeeping.
_SKIP_PARTS = {"__pycache__", "build", "install", "log", ".git"}
_SKIP_SUFFIXES = {".pyc", ".png", ".jpg", ".gif", ".zip", ".gz", ".so", ".a", ".o", ".mcap", ".db3"}


class TriageEntry(BaseModel):
    """One survivor the author judged equivalent or outside the lesson's contract."""

    model_config = ConfigDict(extra="forbid")

    file: str = Field(min_length=1)
    line: str | None = None
    mutant: str | None = None
    #: With ``line``: every mutant of that line (free text such as a package.xml description, which no
    #: program reads: any change is outside the contract, whatever the sample draws).
    every_mutant: bool = False
    key: str | None = None
    reason: str = Field(min_length=10)

    @model_validator(mode="after")
    def _identifies(self) -> TriageEntry:
        if self.every_mutant:
            if self.line is None or self.mutant is not None or self.key is not None:
                raise ValueError("'every_mutant: true' goes with 'line' (the original line) alone, "
                                 "without 'mutant' or 'key'")
        elif self.key is None and (self.line is None or self.mutant is None):
            raise ValueError("an entry names its mutant by 'line' and 'mutant' (the original and mutated lines, "
                             "stripped), by 'key', or every mutant of a line by 'line' and 'every_mutant: true'")
        return self

    def matches(self, mutant: Mutant) -> bool:
        """Whether this entry is about ``mutant``."""
        if self.file != mutant.file:
            return False
        if self.key is not None:
            return self.key == mutant.key
        if self.line.strip() != mutant.original.strip():
            return False
        return self.every_mutant or self.mutant.strip() == mutant.mutated.strip()


class MutationConfig(BaseModel):
    """A lesson's ``mutation.yaml``: which files to mutate, and the triaged survivors."""

    model_config = ConfigDict(extra="forbid")

    files: list[str] | None = None
    survivors: list[TriageEntry] = Field(default_factory=list)


def triage_path(lesson: Lesson) -> Path:
    """``chapters/<lesson>/mutation.yaml``."""
    return lesson.folder / TRIAGE_FILE


def load_config(lesson: Lesson) -> MutationConfig:
    """The lesson's ``mutation.yaml`` (an empty config when there is none).

    Raises:
        LessonFormatError: unreadable YAML or a schema violation, naming the file and field.
    """
    path = triage_path(lesson)
    if not path.is_file():
        return MutationConfig()
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise LessonFormatError(f"{path}: not valid YAML: {yaml_error_text(exc)}",
                                "fix the YAML syntax (indentation, quotes)") from exc
    if data is None:
        return MutationConfig()
    if not isinstance(data, dict):
        raise LessonFormatError(f"{path}: (top level): expected a mapping with 'survivors' (and 'files'), "
                                f"got {type(data).__name__}", "see course/grade/mutate.py for the format")
    try:
        return MutationConfig.model_validate(data)
    except ValidationError as exc:
        raise LessonFormatError(format_validation_error(path, exc),
                                "each survivor has file, line + mutant (or key) and a reason of a sentence; "
                                "see course/grade/mutate.py (TriageEntry)") from exc


@dataclasses.dataclass
class Mutant:
    """One mutant: the reference workspace with ``file`` replaced by ``content``.

    Attributes:
        file: the mutated file, workspace-relative (``src/<pkg>/...`` or a lesson folder's file).
        line: the changed line's number in the original, 1-based.
        original: the original line (no newline).
        mutated: the line in the mutant (no newline; "" when the line was deleted).
        content: the mutant file's whole text.
        number: universalmutator's number of the mutant within its file.
        line_index: 0 for the first mutant of the file with these original and mutated lines, 1 for the
            next (the same change of two identical lines), ...: keeps keys unique.
    """

    file: str
    line: int
    original: str
    mutated: str
    content: str
    number: int = 0
    line_index: int = 0

    @property
    def key(self) -> str:
        """Stable id (12 hex digits): hash of the file's path and the original and mutated lines, not of the
        line number, so a mutant keeps its key (and its triage entry) when lines above it change."""
        text = f"{self.file}\0{self.original.strip()}\0{self.mutated.strip()}\0{self.line_index}"
        return hashlib.sha256(text.encode()).hexdigest()[:12]

    @property
    def content_hash(self) -> str:
        """sha256 of the path and the mutant file's text."""
        return hashlib.sha256(f"{self.file}\0{self.content}".encode()).hexdigest()

    def diff(self, original_text: str) -> str:
        """Unified diff of the original file and this mutant (``a/<file>``, ``b/<file>``)."""
        return "".join(difflib.unified_diff(original_text.splitlines(keepends=True),
                                            self.content.splitlines(keepends=True),
                                            f"a/{self.file}", f"b/{self.file}", n=2))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: key, file, line, original line and mutated line (not the whole content)."""
        return {"key": self.key, "file": self.file, "line": self.line, "original": self.original,
                "mutant": self.mutated}


def require_tool() -> None:
    """Raise unless universalmutator can be imported here.

    Raises:
        MissingRequirement: with the install command as the hint.
    """
    if importlib.util.find_spec("universalmutator") is None:
        raise MissingRequirement("dev mutate needs universalmutator, which is not installed",
                                 "pip install 'ros2course[mutate]' (or pip install universalmutator)")


def _own_starter(lesson: Lesson) -> dict[str, Path]:
    folder = lesson.starter_dir
    if not folder.is_dir():
        return {}
    return {p.relative_to(folder).as_posix(): p for p in folder.rglob("*") if p.is_file()}


def _others_starters(lesson: Lesson) -> set[str]:
    """Paths the starters of the lessons it includes, and every other lesson's own starter, give:
    those lessons teach (and their graders answer for) these files."""
    folders = list(lesson.included_starters)
    try:
        folders += [other.starter_dir for other in load_catalog(lesson.folder.parent.parent).lessons
                    if other.id != lesson.id]
    except CourseError:
        pass  # a lesson outside a catalog: its included starters only
    return {p.relative_to(folder).as_posix() for folder in folders if folder.is_dir()
            for p in folder.rglob("*") if p.is_file()}


def _mutable(path: Path) -> bool:
    if path.suffix.lower() in _SKIP_SUFFIXES or any(part in _SKIP_PARTS or part.endswith(".egg-info")
                                                     for part in path.parts):
        return False
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return False
    return bool(text.strip())


def lesson_files(lesson: Lesson, reference: Path, config: MutationConfig | None = None) -> list[str]:
    """The reference files to mutate, workspace-relative, sorted.

    With ``files`` in ``mutation.yaml``: the files of the reference workspace matching those globs.
    Otherwise the lesson's own work: each text file under the lesson's packages and folders that its
    own starter gives with different content (the learner completes it) or does not give at all (the
    learner writes it), leaving out the files of the lessons it includes (``starter_includes``: their
    graders answer for them) and the finished files its starter hands out (``starter_solutions``, e.g.
    sas-robot-driver's ``sas_lite.py``, "do not change it").

    Args:
        reference: a reference workspace of the lesson (:func:`ros2course.build.reference.reference_workspace`).
        config: the lesson's ``mutation.yaml`` (None: read it).

    Raises:
        LessonFormatError: ``files`` matches nothing, or mutation.yaml is malformed.
    """
    config = config if config is not None else load_config(lesson)
    every = sorted(p.relative_to(reference).as_posix() for root in lesson.workspace_paths
                   if (reference / root).exists() for p in (reference / root).rglob("*")
                   if p.is_file() and _mutable(p))
    if config.files is not None:
        chosen = [rel for rel in every if any(fnmatch.fnmatch(rel, glob) for glob in config.files)]
        if not chosen:
            raise LessonFormatError(f"{triage_path(lesson)}: files: {config.files} match no file of the reference",
                                    f"name files relative to the workspace, e.g. {every[0] if every else 'src/<pkg>/...'}")
        return chosen
    own, included = _own_starter(lesson), _others_starters(lesson)
    given = tuple(lesson.starter_solutions)
    out = []
    for rel in every:
        if any(rel == folder or rel.startswith(folder + "/") for folder in given):
            continue
        if rel in own:
            if own[rel].read_bytes() != (reference / rel).read_bytes():
                out.append(rel)
        elif rel not in included:
            out.append(rel)
    return out


def _changed_line(original: list[str], mutated: list[str]) -> tuple[int, str, str]:
    """``(1-based line, original line, mutated line)`` of the first difference (regex mutants change one line)."""
    matcher = difflib.SequenceMatcher(a=original, b=mutated, autojunk=False)
    for tag, a0, a1, b0, b1 in matcher.get_opcodes():
        if tag == "equal":
            continue
        old = "".join(original[a0:a1]).rstrip("\n") if a1 > a0 else ""
        new = "".join(mutated[b0:b1]).rstrip("\n") if b1 > b0 else ""
        return a0 + 1, old, new
    return 0, "", ""


#: Files whose ``#`` starts a comment line: shell scripts, CMake, ROS interface definitions, YAML, setup.cfg.
_HASH_COMMENT_SUFFIXES = {".sh", ".bash", ".cmake", ".msg", ".srv", ".action", ".yaml", ".yml", ".cfg", ".toml"}
_HEREDOC = re.compile(r"<<-?\s*['\"]?[A-Za-z_]")


def _xml_shape(text: str) -> Any:
    """An XML document as nested ``(tag, attributes, stripped text, children)``, or None when it does not parse.

    Comments, whitespace and text between elements (``tail``, and the text of an element that has
    children) are not part of it: ROS reads a package.xml's elements and the text of its leaf
    elements (catkin_pkg's parser, REP 149), and Fast DDS an XML profile the same way (its parser,
    on tinyxml2, asks leaf elements for their text).
    """
    def shape(element: ET.Element) -> Any:
        text = (element.text or "").strip() if len(element) == 0 else ""
        return (element.tag, sorted(element.attrib.items()), text, [shape(child) for child in element])
    try:
        return shape(ET.fromstring(text))
    except ET.ParseError:
        return None


def equivalent_mutant(rel: str, original: str, mutated: str, old_line: str, new_line: str) -> bool:
    """Whether a mutant changes nothing a program can see, so it is dropped like universalmutator's own
    equivalents (its Python handler drops mutants with the original's bytecode; its TCE, C++ duplicates).

    Two kinds, for the files universalmutator mutates with its universal rules only: a changed comment
    line (``#`` comments of shell scripts, CMake, ``.msg``/``.srv``/``.action`` definitions, YAML,
    setup.cfg and TOML such as pyproject.toml; not the ``#!`` line, and never in a script with a here-document, where ``#`` lines are
    data), and an XML file (package.xml, launch XML) whose mutant parses to the same elements,
    attributes and texts (:func:`_xml_shape`). A mutant that breaks the XML is invalid (:func:`invalid_mutant`).

    Args:
        rel: the file's path in the reference (its suffix and name pick the rule).
        original, mutated: the whole file before and after.
        old_line, new_line: the changed line before and after (:func:`_changed_line`).
    """
    name = Path(rel).name
    suffix = Path(rel).suffix.lower()
    if suffix == ".xml":
        before = _xml_shape(original)
        return before is not None and _xml_shape(mutated) == before
    if suffix in _HASH_COMMENT_SUFFIXES or name == "CMakeLists.txt":
        if suffix in {".sh", ".bash"} and _HEREDOC.search(original):
            return False
        old, new = old_line.lstrip(), new_line.lstrip()
        return (old.startswith("#") and new.startswith("#") and not old.startswith("#!")
                and "\n" not in old_line and "\n" not in new_line)
    return False


def invalid_mutant(rel: str, mutated: str) -> bool:
    """Whether a mutant is not a program at all, so it is dropped as universalmutator's Python handler
    drops a ``.py`` mutant that does not compile: an XML file (package.xml, launch XML) that no longer
    parses. colcon (catkin_pkg) rejects such a package.xml before any check runs, so it would only be
    "killed by build", telling nothing of the grader, and package.xml's character-level mutants are
    mostly such (simplest-python-package: 25 of a 30-mutant sample), crowding a sample out.

    Args:
        rel: the file's path in the reference (its suffix picks the rule).
        mutated: the whole mutated file.
    """
    return Path(rel).suffix.lower() == ".xml" and _xml_shape(mutated) is None


def generate_file_mutants(reference: Path, rel: str) -> list[Mutant]:
    """Every mutant universalmutator makes of ``reference/rel``, in its order.

    Python files are checked by universalmutator's Python handler (mutants that do not compile, or
    compile to the original's bytecode, are dropped); other files are not checked (``--noCheck``),
    but an XML mutant that does not parse is dropped as invalid (:func:`invalid_mutant`), and a
    mutant of a comment line or an XML mutant with the same elements as equivalent
    (:func:`equivalent_mutant`).

    Raises:
        MissingRequirement: universalmutator is not installed.
        CourseError: universalmutator failed on the file (its output's last line in the message).
    """
    require_tool()
    source = reference / rel
    original = source.read_text(encoding="utf-8")
    language = LANGUAGES.get(source.suffix.lower())
    with tempfile.TemporaryDirectory(prefix="ros2course-mutants-") as tmp:
        work = Path(tmp)
        copy = work / source.name
        shutil.copyfile(source, copy)
        script = "import sys; from universalmutator.genmutants import main; sys.argv[0] = 'mutate'; main()"
        argv = [sys.executable, "-c", script, copy.name]
        if language:
            argv.append(language)
        argv += ["--mutantDir", "mutants"]
        if language not in CHECKED_LANGUAGES:
            argv.append("--noCheck")
        run = subprocess.run(argv, cwd=work, capture_output=True, text=True, timeout=600, check=False)
        folder = work / "mutants"
        if run.returncode != 0 or not folder.is_dir():
            last = (run.stderr or run.stdout).strip().splitlines()[-1:] or ["no output"]
            raise CourseError(f"universalmutator failed on {rel} (exit code {run.returncode}): {last[0]}",
                              "run `mutate FILE --mutantDir DIR` on that file to see why")
        stem, suffix = copy.stem, copy.suffix
        found = []
        for path in folder.iterdir():
            middle = path.name[len(stem) + len(".mutant."):len(path.name) - len(suffix)] if suffix else \
                path.name[len(stem) + len(".mutant."):]
            if path.name.startswith(f"{stem}.mutant.") and middle.isdigit():
                found.append((int(middle), path.read_text(encoding="utf-8", errors="replace")))
    lines = original.splitlines(keepends=True)
    out: list[Mutant] = []
    seen: dict[tuple[str, str], int] = {}
    for number, content in sorted(found):
        if content == original:
            continue
        line, old, new = _changed_line(lines, content.splitlines(keepends=True))
        if invalid_mutant(rel, content) or equivalent_mutant(rel, original, content, old, new):
            continue
        index = seen.get((old.strip(), new.strip()), 0)
        seen[(old.strip(), new.strip())] = index + 1
        out.append(Mutant(rel, line, old, new, content, number, index))
    return out


def generate_mutants(lesson: Lesson, reference: Path, config: MutationConfig | None = None) -> list[Mutant]:
    """The mutants of every file of :func:`lesson_files`, file by file.

    Raises:
        MissingRequirement: universalmutator is not installed.
        LessonFormatError: a malformed ``mutation.yaml``.
        CourseError: the lesson has no file to mutate, or universalmutator failed.
    """
    files = lesson_files(lesson, reference, config)
    if not files:
        raise CourseError(f"lesson {lesson.id} has no reference file to mutate",
                          f"name them with 'files:' in {triage_path(lesson)}")
    return [m for rel in files for m in generate_file_mutants(reference, rel)]


def sample_mutants(mutants: list[Mutant], count: int | None, seed: int) -> list[Mutant]:
    """``count`` mutants picked with ``random.Random(seed)`` (all when ``count`` is None or not smaller).

    Raises:
        CourseError: ``count`` below 1.
    """
    if count is None or count >= len(mutants):
        return list(mutants)
    if count < 1:
        raise CourseError(f"--sample must be at least 1 (got {count})", "e.g. --sample 30")
    picked = set(random.Random(seed).sample(range(len(mutants)), count))
    return [m for i, m in enumerate(mutants) if i in picked]


def classify(result: LessonResult) -> tuple[str, list[str]]:
    """``(outcome, lost checks)`` of a mutant's grading (see the module docstring for the outcomes)."""
    if result.status == Status.GRADER_ERROR:
        return GRADER_ERROR, []
    if result.status == Status.NOT_GRADABLE:
        message = result.message or ""
        if message.startswith("timed out"):
            return TIMED_OUT, []
        # the build failed, or colcon could not even read the package (a broken package.xml): the
        # checks never ran, so it says nothing about the grader
        return KILLED_BY_BUILD, ["build"]
    lost = [c.id for c in result.checks if c.points < c.max_points]
    if "build" in lost:
        return KILLED_BY_BUILD, lost
    if result.score >= result.max_score and not lost:
        return SURVIVED, []
    return KILLED, lost


def _hash_files(paths: list[Path], root: Path) -> str:
    digest = hashlib.sha256()
    for path in sorted(paths):
        if path.is_file() and "__pycache__" not in path.parts:
            digest.update(f"{path.relative_to(root)}\0".encode() + path.read_bytes() + b"\0")
    return digest.hexdigest()


def grader_hash(lesson: Lesson) -> str:
    """sha256 of the grader's source: its module, its course's helper modules and data, the kit and the engine that runs it."""
    root = content_root()
    paths = [root / "graders" / f"{lesson.grader}.py", *(root / "graders").glob("_*.py"),
             *(root / "graders" / "data").rglob("*"), *(Path(__file__).resolve().parents[1] / "kit").rglob("*.py"),
             *(Path(__file__).resolve().parents[1] / "grade").glob("engine.py"),
             *(Path(__file__).resolve().parents[1] / "run").rglob("*.py")]
    return _hash_files(paths, root if all(p.is_relative_to(root) for p in paths) else Path("/"))


def course_hash(reference: Path, lesson: Lesson) -> str:
    """sha256 of the reference workspace a mutant starts from and of the lesson's ``lesson.yaml``."""
    digest = hashlib.sha256(_hash_files([p for p in reference.rglob("*")], reference).encode())
    digest.update((lesson.folder / "lesson.yaml").read_bytes())
    return digest.hexdigest()


def cache_key(grader: str, course: str, mutant: Mutant) -> str:
    """The cache's key of a mutant's outcome: (grader source, course content, mutant content)."""
    return hashlib.sha256(f"{grader}\0{course}\0{mutant.content_hash}".encode()).hexdigest()[:32]


@dataclasses.dataclass
class Graded:
    """A mutant and how its grading ended."""

    mutant: Mutant
    outcome: str
    lost: list[str]
    score: float = 0.0
    max_score: float = 0.0
    message: str = ""
    cached: bool = False
    triaged: str = ""  #: the triage reason when ``mutation.yaml`` lists this survivor

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the mutant's fields, outcome, lost checks, score, message, cached, triage reason."""
        return {**self.mutant.to_dict(), "outcome": self.outcome, "lost": self.lost, "score": self.score,
                "max_score": self.max_score, "message": self.message, "cached": self.cached,
                "triaged": self.triaged}


def set_aside(mutants: list[Mutant], config: MutationConfig) -> tuple[list[Mutant], list[Mutant]]:
    """``(to grade, set aside)``: the mutants of lines ``mutation.yaml`` triages whole (``every_mutant``)
    are set aside before sampling. Whatever they change, the author judged it outside the contract (a
    script's ``#!`` line the checker never reads, a package.xml description), so grading them would
    only spend the sample (inspect-topics: 18 of its first 30 were such)."""
    whole = [e for e in config.survivors if e.every_mutant]
    aside = [m for m in mutants if any(e.matches(m) for e in whole)]
    keys = {m.key for m in aside}
    return [m for m in mutants if m.key not in keys], aside


def apply_triage(graded: list[Graded], config: MutationConfig, every: list[Mutant]) -> list[TriageEntry]:
    """Mark triaged survivors (``Graded.triaged``); return the *stale* entries (matching no current mutant).

    Args:
        graded: the graded mutants (only survivors get marked).
        config: the lesson's ``mutation.yaml``.
        every: every mutant generated now (not only the sample): an entry is stale only when it matches none.
    """
    for item in graded:
        if item.outcome == SURVIVED:
            entry = next((e for e in config.survivors if e.matches(item.mutant)), None)
            if entry is not None:
                item.triaged = entry.reason
    return [e for e in config.survivors if not any(e.matches(m) for m in every)]


@dataclasses.dataclass
class LessonMutation:
    """What ``dev mutate`` found for one lesson.

    Attributes:
        generated: mutants universalmutator made of the lesson's files.
        graded: the graded ones (all, or the ``--sample``), with outcomes.
        stale: ``mutation.yaml`` entries matching no generated mutant.
        sampled: True when ``graded`` is a sample.
        seconds: wall time of the lesson (generation, grading, classification), seconds.
        set_aside: generated mutants of lines ``mutation.yaml`` triages whole (``every_mutant``):
            never sampled nor graded (:func:`set_aside`), so a sample is spent on mutants that count.
    """

    lesson: str
    generated: int
    graded: list[Graded]
    stale: list[TriageEntry]
    sampled: bool
    seconds: float = 0.0
    diffs: dict[str, str] = dataclasses.field(default_factory=dict)  #: survivor key -> unified diff
    set_aside: int = 0

    def count(self, outcome: str) -> int:
        """How many graded mutants ended with ``outcome`` (one of :data:`OUTCOMES`)."""
        return sum(g.outcome == outcome for g in self.graded)

    @property
    def triaged(self) -> int:
        """How many survivors ``mutation.yaml`` triages."""
        return sum(bool(g.triaged) for g in self.graded)

    @property
    def score(self) -> float | None:
        """killed / (graded - killed by build - triaged), or None when nothing counts."""
        denominator = len(self.graded) - self.count(KILLED_BY_BUILD) - self.triaged
        return self.count(KILLED) / denominator if denominator > 0 else None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (counts, score, stale entries) and every graded mutant (``mutation.json``)."""
        return {"lesson": self.lesson, "generated": self.generated, "graded": len(self.graded),
                "sampled": self.sampled, "killed": self.count(KILLED), "killed_by_build": self.count(KILLED_BY_BUILD),
                "survived": self.count(SURVIVED), "triaged": self.triaged, "timed_out": self.count(TIMED_OUT),
                "grader_error": self.count(GRADER_ERROR), "score": self.score, "seconds": round(self.seconds, 1),
                "set_aside": self.set_aside,
                "stale": [e.model_dump(exclude_none=True) for e in self.stale],
                "mutants": [g.to_dict() for g in self.graded]}


def course_version() -> str:
    """The current course's version (``course.yaml``), "" for a course without a manifest."""
    root = content_root()
    return load_manifest(root).version if (root / MANIFEST).is_file() else ""


def write_score(lesson: Lesson, found: LessonMutation, measured: dict[str, str] | None = None) -> Path | None:
    """Record ``found``'s counts and score in ``chapters/<lesson>/mutation-score.json``; its path, or None.

    The file lives with the lesson, like its ``mutation.yaml``, so that ``dev validate``
    (:func:`describe_score`) and whoever reads the course see the grader's last
    measured strength; commit it with the lesson. Every mutant's outcome goes to
    ``mutation-outcomes.json`` beside it. ``measured`` (``date``, ``fingerprint``) names
    the run the outcomes come from when it is not now (a re-triage of an old run keeps
    its date and its grader fingerprint). None when the lesson folder is read-only (an
    installed course): the run's ``mutation.json`` still has it all.
    """
    from ros2course.grade.fingerprint import grader_fingerprint  # noqa: PLC0415 - reads the course's files

    measured = measured or {"date": dt.date.today().isoformat(), "fingerprint": grader_fingerprint(lesson)}
    fingerprint = measured["fingerprint"]
    data = {key: value for key, value in found.to_dict().items() if key not in ("mutants", "stale", "lesson")}
    data.update(date=measured["date"], course_version=course_version(), fingerprint=fingerprint,
                survivors=sorted(f"{g.mutant.file}:{g.mutant.line} ({g.mutant.key})" for g in found.graded
                                 if g.outcome == SURVIVED and not g.triaged))
    # every mutant's outcome, committed with the lesson: the figure can be checked and re-derived (issue 37)
    outcomes = {"fingerprint": fingerprint, "date": data["date"],
                "mutants": [{"key": g.mutant.key, "file": g.mutant.file, "line": g.mutant.line,
                             "original": g.mutant.original.strip(), "mutant": g.mutant.mutated.strip(),
                             "outcome": g.outcome, "lost": g.lost, **({"triaged": g.triaged} if g.triaged else {})}
                            for g in sorted(found.graded, key=lambda g: (g.mutant.file, g.mutant.line, g.mutant.key))]}
    path = lesson.folder / SCORE_FILE
    try:
        atomic_write_text(path, json.dumps(data, indent=1) + "\n")
        atomic_write_text(lesson.folder / OUTCOMES_FILE, json.dumps(outcomes, indent=0) + "\n")
    except OSError:
        return None
    return path


#: Below this many counted mutants a score is too small to judge a grader by (issue 37).
MIN_COUNTED = 20


@dataclasses.dataclass
class RecordedScore:
    """A lesson's recorded mutation run (``mutation-score.json``), as the figures the doc and ``dev validate`` show.

    Attributes:
        counted: graded - killed by build - triaged (the score's denominator).
        tuned: killed / counted (triage applied), None when nothing counts.
        raw: killed / (graded - killed by build), before any triage, None when nothing was graded.
        stale: "" when measured under the lesson's current grader fingerprint, else why not, with the run's date.
    """

    data: dict
    counted: int
    tuned: float | None
    raw: float | None
    stale: str

    @property
    def too_small(self) -> bool:
        """Fewer than :data:`MIN_COUNTED` counted mutants."""
        return self.counted < MIN_COUNTED


def recorded_score(lesson: Lesson) -> RecordedScore | None:
    """The lesson's recorded mutation run (:func:`write_score`), or None when there is none or it is unreadable."""
    try:
        data = json.loads((lesson.folder / SCORE_FILE).read_text(encoding="utf-8"))
        graded, by_build, triaged, killed = (int(data[k]) for k in ("graded", "killed_by_build", "triaged", "killed"))
    except (OSError, ValueError, KeyError, TypeError):
        return None
    from ros2course.grade.fingerprint import grader_fingerprint  # noqa: PLC0415 - reads the course's files

    counted = graded - by_build - triaged
    judged = graded - by_build
    recorded, now = data.get("fingerprint"), grader_fingerprint(lesson)
    when = data.get("date", "?")
    stale = ("" if recorded == now else
             f"stale: graded on {when}, before grader fingerprints were recorded" if not recorded else
             f"stale: graded on {when} under grader fingerprint {recorded}, now {now}")
    return RecordedScore(data, counted, killed / counted if counted > 0 else None,
                         killed / judged if judged > 0 else None, stale)


def _share(value: float | None) -> str:
    return "n/a" if value is None else f"{100 * value:.0f} %"


def score_text(lesson: Lesson) -> str:
    """The lesson's last mutation score in a few words (a table cell): the raw kill rate, the score after
    triage and its counted denominator, ``too small`` below :data:`MIN_COUNTED`, ``stale`` when the grader
    changed since (``"raw 62 %, triaged 100 % of 13 counted (too small); stale"``), or ``"not measured"``."""
    row = recorded_score(lesson)
    if row is None:
        return "not measured"
    return (f"raw {_share(row.raw)}, triaged {_share(row.tuned)} of {row.counted} counted"
            + (" (too small)" if row.too_small else "") + ("; stale" if row.stale else ""))


def describe_score(lesson: Lesson) -> str:
    """One line on the lesson's last mutation score (:func:`write_score`), or how to measure it."""
    how = f"ros2course dev mutate {lesson.id} --sample 30"
    row = recorded_score(lesson)
    if row is None:
        return f"{lesson.id}: grader strength not measured ({how})"
    data = row.data
    graded = (f"{data['graded']} of {data['generated']} mutants (a sample)" if data.get("sampled")
              else f"all {data['generated']} mutants")
    small = f"; {row.counted} counted mutants are too few to judge by (< {MIN_COUNTED})" if row.too_small else ""
    stale = f"; {row.stale}: {how}" if row.stale else ""
    left = f"; {len(data.get('survivors', []))} survivor(s) not triaged" if data.get("survivors") else ""
    return (f"{lesson.id}: grader strength {_share(row.tuned)} after triage, {_share(row.raw)} raw "
            f"({data['killed']} of {row.counted} counted mutants killed; "
            f"{graded}, {data['triaged']} triaged, {data['killed_by_build']} killed by the build; "
            f"dev mutate {data.get('date', '?')}{left}{small}{stale})")
