"""Similar submissions of a batch-graded class (issues 21, 39), with ``copydetect``.

Each student's source files for a lesson are fingerprinted with copydetect's winnowing
(:class:`copydetect.CodeFingerprint`: Pygments tokens, names and string literals normalised, so
renaming a variable or a package does not hide a copy). Code every student was given or had
generated is *boilerplate*: every k-gram of it is removed from the students' fingerprints before
comparing (so a score is over the tokens left after boilerplate), and a file handed in unchanged
is not compared at all. Boilerplate is

* every lesson's starter files (and the ``solutions/`` files starters offer whole), always;
* the reference solutions (``solutions/``, the tutorial's listings the learner is told to type in)
  unless ``exclude_reference=False``;
* what the lesson's tools generate (issue 39): the files ``ros2 pkg create`` writes for
  ``ament_python``, ``ament_cmake`` and ``cmake`` packages (``setup.py``, ``setup.cfg``,
  ``package.xml``, the ``test/`` files for ament_copyright, ament_flake8 and ament_pep257, the
  ``--node-name`` sample node, ``CMakeLists.txt``, the C++ node and library files), rendered from
  ros2pkg's own templates (:func:`generated_files`). colcon itself writes no sources: its
  ``build``/``install``/``log`` folders are never read (:data:`SKIP_DIRS`).

Then code *much of the section* shares is ignored too (:func:`common_limit`, Moss's ``-m``), and a
pair is flagged only when it is at least :data:`THRESHOLD` alike over what is left AND shares at
least :data:`MIN_SHARED_TOKENS` tokens of it: a pair whose shared code is all boilerplate is no pair,
nor one sharing a line or two.

Comparing every pair of files with :func:`copydetect.compare_files` is quadratic (a class
of 300 for one lesson is 44,850 pairs of students); instead an inverted index of
fingerprints counts the shared fingerprints of every pair of files at once, and only pairs
sharing at least half the threshold go to ``compare_files`` for the exact score and the
matching fragments. Comparisons stay within one lesson.

This only FLAGS pairs for a person to look at; it never changes a grade.
"""

from __future__ import annotations

import collections
import dataclasses
import functools
import hashlib
import importlib.machinery
import importlib.resources
import importlib.util
import io
import itertools
import re
import tarfile
import types
import zipfile
from collections.abc import Iterator
from pathlib import Path, PurePosixPath

from ros2course.grade.results import LessonResult

#: Pairs at or above this similarity (0..1) are flagged.
THRESHOLD = 0.8
#: Files larger than this (bytes) are not compared (generated data, vendored code).
MAX_BYTES = 200_000
#: Source files compared per student and lesson (the largest count first; a workspace of generated files is capped).
MAX_FILES = 40
#: Folders never compared: colcon's outputs and caches.
SKIP_DIRS = {"build", "install", "log", ".git", "__pycache__", ".venv", "node_modules"}
#: Source files compared.
EXTENSIONS = {".py", ".cpp", ".hpp", ".h", ".cc", ".c", ".txt", ".xml", ".yaml", ".yml", ".launch", ".msg", ".srv",
              ".sh", ".cfg", ".toml"}
#: Archive suffixes read in memory (never extracted), as :mod:`ros2course.batch.archive` names students.
ARCHIVES = (".tar.gz", ".tgz", ".zip")
#: Fragments of a pair kept for the report, and characters per fragment.
MAX_FRAGMENTS, FRAGMENT_CHARS = 6, 1500
#: copydetect's k-gram length (noise threshold) and guarantee threshold (its defaults).
_NOISE, _GUARANTEE = 25, 30
#: A pair is flagged only when its best files share at least this many copydetect tokens beyond
#: boilerplate and common code. A copydetect token is one character of its filtered code, in which a
#: name or a string literal counts 1 (quotes 1 each) and whitespace and comments 0: the line
#: ``self.timer = self.create_timer(0.5, self.tick)`` is ``self.V=self.V(0.5,self.V)``, 25 tokens;
#: the 40 lines of tests/test_similarity.py's shared block are 514, ~15 a line with blank lines.
#: 120 is about 8 lines: a function's worth of code, well above copydetect's own noise threshold
#: (25, the shortest match it can see), while what students add alike without copying stays below
#: it (a launch folder in ``setup.py``'s ``data_files``: 26; a ``<depend>`` line in package.xml: 17).
MIN_SHARED_TOKENS = 120


@dataclasses.dataclass
class SimilarPair:
    """Two students whose submissions for ``lesson`` are alike.

    Attributes:
        lesson: the lesson id.
        first, second: the student ids.
        score: similarity 0..1: the mean of copydetect's two directions (copied tokens / compared
            tokens of each file) over the pair's most alike files, both counted after boilerplate and
            common code are left out.
        files: (first's file, second's file), paths relative to the submission.
        fragments: (text in first's file, text in second's file) of the matching code, at most
            :data:`MAX_FRAGMENTS` of :data:`FRAGMENT_CHARS` characters.
        shared_tokens: what the two files share beyond boilerplate and common code, in copydetect
            tokens (:data:`MIN_SHARED_TOKENS` says what one is) of the first file.
    """

    lesson: str
    first: str
    second: str
    score: float
    files: tuple[str, str]
    fragments: list[tuple[str, str]]
    shared_tokens: int = 0


@dataclasses.dataclass
class Comparison:
    """What :func:`similar_pairs` compared and found.

    Attributes:
        pairs: flagged pairs, most alike first.
        students: lesson id -> number of students whose sources were found.
        files: source files compared: those left with tokens of their own after boilerplate.
        boilerplate_files: course files whose fingerprints were left out (starter, reference).
        generated_files: files ``ros2 pkg create`` writes, rendered from ros2pkg's templates and left out
            (every variant counted: with and without a node, a library, 0 to 4 dependencies).
        generated_from: where those templates were read, or why there were none (one line).
        seconds: wall time, seconds.
    """

    pairs: list[SimilarPair]
    students: dict[str, int]
    files: int
    boilerplate_files: int
    seconds: float
    generated_files: int = 0
    generated_from: str = ""


def _wanted(rel: str, size: int) -> bool:
    pure = PurePosixPath(rel)
    return (pure.suffix in EXTENSIONS and size <= MAX_BYTES
            and not any(part in SKIP_DIRS or part.startswith(".") for part in pure.parts[:-1]))


def _decode(data: bytes) -> str | None:
    if b"\0" in data:
        return None
    return data.decode("utf-8", errors="replace")


def _folder_files(folder: Path) -> Iterator[tuple[str, str]]:
    """(path relative to ``folder``, text) of its source files; links, FIFOs and devices skipped."""
    stack = [folder]
    while stack:
        current = stack.pop()
        try:
            entries = sorted(current.iterdir())
        except OSError:
            continue
        for entry in entries:
            if entry.is_symlink():
                continue
            if entry.is_dir():
                if entry.name not in SKIP_DIRS and not entry.name.startswith("."):
                    stack.append(entry)
                continue
            rel = entry.relative_to(folder).as_posix()
            try:
                if not entry.is_file() or not _wanted(rel, entry.stat().st_size):
                    continue
                text = _decode(entry.read_bytes())
            except OSError:
                continue
            if text is not None:
                yield rel, text


def _archive_files(archive: Path) -> Iterator[tuple[str, str]]:
    """(member name, text) of an archive's source files, read in memory (nothing is extracted)."""
    try:
        if archive.name.lower().endswith(".zip"):
            with zipfile.ZipFile(archive) as handle:
                for info in handle.infolist()[:20_000]:
                    if not info.is_dir() and ".." not in PurePosixPath(info.filename).parts \
                            and _wanted(info.filename, info.file_size):
                        text = _decode(handle.read(info))
                        if text is not None:
                            yield info.filename, text
        else:
            with tarfile.open(archive, "r:*") as handle:
                for count, member in enumerate(handle):
                    if count >= 20_000:
                        break
                    if member.isfile() and ".." not in PurePosixPath(member.name).parts \
                            and _wanted(member.name, member.size):
                        extracted = handle.extractfile(member)
                        text = _decode(extracted.read()) if extracted is not None else None
                        if text is not None:
                            yield member.name, text
    except (OSError, zipfile.BadZipFile, tarfile.TarError, EOFError, ValueError):
        return


def read_sources(entry: Path, lesson_paths: list[str]) -> dict[str, str]:
    """A submission's source files for one lesson: relative path -> text.

    Args:
        entry: the student's entry of the submissions folder: a folder, or a ``.zip``/``.tar.gz``/``.tgz``
            archive read in memory.
        lesson_paths: the lesson's workspace paths (``src/<package>``, ``python/minimalist_package``, a file);
            when some file lies under (or is) one of them only those files are kept, else every source file.

    Files over :data:`MAX_BYTES`, binary files, build/install/log folders and links are left out; at most
    :data:`MAX_FILES` files are kept. Never raises on unreadable input (it yields fewer files).
    """
    found = list(_folder_files(entry) if entry.is_dir() else _archive_files(entry))
    marks = [p.strip("/") for p in lesson_paths if p.strip("/")]
    inside = [(rel, text) for rel, text in found
              if any(f"/{mark}/" in f"/{rel}" or f"/{rel}".endswith(f"/{mark}") for mark in marks)]
    chosen = inside or found
    return dict(sorted(chosen[:MAX_FILES]))


def student_entry(submissions: Path, student: str) -> Path | None:
    """The entry of ``student`` in ``submissions`` (folder or archive), or None."""
    candidate = submissions / student
    if candidate.is_dir():
        return candidate
    for suffix in ARCHIVES:
        candidate = submissions / f"{student}{suffix}"
        if candidate.is_file():
            return candidate
    return None


def boilerplate_folders(exclude_reference: bool) -> list[Path]:
    """Folders and files of code the course gives every student (its fingerprints do not count).

    Every lesson's starter and the ``solutions/`` files starters offer whole (a later lesson's
    workspace legitimately holds an earlier lesson's starter), and with ``exclude_reference`` every
    reference solution (``solutions/``: the tutorial's listings, meant to be typed in).
    """
    from ros2course.lesson.catalog import load_catalog  # noqa: PLC0415 - start time: the catalog (yaml) only for a course's own files

    catalog = load_catalog()
    solutions = catalog.course.solutions
    out: list[Path] = []
    for lesson in catalog.lessons:
        out += [*lesson.starter_layers, *(solutions / rel for rel in lesson.starter_solutions)]
    if exclude_reference:
        out = [path for path in out if not path.is_relative_to(solutions)] + [solutions]
    return sorted({path for path in out if path.exists()})


#: Pygments lexer per suffix (naming it skips Pygments' search by file name, most of a fingerprint's cost);
#: files of other suffixes (.msg, .srv, a .txt that is not CMakeLists.txt) are compared untokenized.
LEXERS = {".py": "python", ".cpp": "cpp", ".hpp": "cpp", ".h": "cpp", ".cc": "cpp", ".c": "c", ".xml": "xml",
          ".launch": "xml", ".yaml": "yaml", ".yml": "yaml", ".sh": "bash", ".cfg": "ini", ".toml": "toml"}


def _language(rel: str) -> str | None:
    pure = PurePosixPath(rel)
    return "cmake" if pure.name == "CMakeLists.txt" else LEXERS.get(pure.suffix)


def _stable_kgram_hashes(string: str, k: int):
    """Every k-gram hash of ``string``, as :func:`copydetect.utils.hashed_kgrams` computes them but the same in
    every process: 64-bit BLAKE2b of the k-gram's UTF-8, as a signed numpy int64 array (copydetect's shape)."""
    import numpy  # noqa: PLC0415 - copydetect's own dependency, loaded with it

    digest = hashlib.blake2b
    return numpy.array([int.from_bytes(digest(string[offset:offset + k].encode("utf-8", "surrogatepass"),
                                              digest_size=8).digest(), "little", signed=True)
                        for offset in range(len(string) - k + 1)], dtype=numpy.int64)


@functools.cache
def _copydetect() -> types.ModuleType:
    """copydetect, with k-gram hashes that do not change from one process to the next.

    copydetect 0.5 hashes k-grams with Python's ``hash()`` of ``str``, which is salted per process
    (PYTHONHASHSEED): winnowing then keeps other k-grams in every run, and two reports of one class could
    flag different pairs. Its ``utils.hashed_kgrams`` (looked up at call time by its own
    ``get_document_fingerprints``) is replaced once, for the whole process, by :func:`_stable_kgram_hashes`;
    copydetect has no option for it, and nothing else in this process uses copydetect.
    """
    import copydetect  # noqa: PLC0415 - slow to import
    import copydetect.utils  # noqa: PLC0415 - copydetect is optional (the similarity extra): only when it is used

    copydetect.utils.hashed_kgrams = _stable_kgram_hashes
    return copydetect


def _fingerprint(rel: str, text: str):
    """copydetect's fingerprint of one file (no boilerplate removed yet: :func:`_strip` does), or None."""
    CodeFingerprint = _copydetect().CodeFingerprint  # noqa: N806 - copydetect's class

    language = _language(rel)
    try:
        return CodeFingerprint(rel, _NOISE, _GUARANTEE, fp=io.StringIO(text), filter=language is not None,
                               language=language)
    except Exception:  # noqa: BLE001 - a file Pygments cannot tokenize is simply not compared
        return None


def _strip(fingerprint, drop: frozenset[int] | set[int]) -> None:
    """Remove the hashes in ``drop`` from ``fingerprint`` (in place), so copydetect neither matches them nor
    counts their tokens: ``token_coverage``, the denominator of its similarity, is recomputed over what is left.

    copydetect's own ``boilerplate=`` argument intersects with ``assume_unique`` on hashes that may repeat and
    only ever sees the *winnowed* hashes of the boilerplate; here every k-gram of the boilerplate is dropped.
    """
    from copydetect.utils import get_token_coverage  # noqa: PLC0415 - slow to import

    gone = [value for value in fingerprint.hash_idx if int(value) in drop]
    if gone:
        for value in gone:
            del fingerprint.hash_idx[value]
        fingerprint.hashes = set(fingerprint.hash_idx)
        fingerprint.token_coverage = get_token_coverage(fingerprint.hash_idx, fingerprint.k,
                                                        len(fingerprint.filtered_code))


def _kgrams(rel: str, text: str) -> set[int]:
    """Every k-gram hash of ``text`` as copydetect tokenizes it (not only the winnowed ones)."""
    fingerprint = _fingerprint(rel, text)
    if fingerprint is None or len(fingerprint.filtered_code) < _NOISE:
        return set()
    return {int(value) for value in _stable_kgram_hashes(fingerprint.filtered_code, _NOISE)}


# --- What `ros2 pkg create` generates -----------------------------------------------------------------------

#: The package name, node name, maintainer... the templates are rendered with. Any will do: copydetect turns
#: names and string literals into one token each and drops XML text, so a student's own package name,
#: node name and maintainer match these (checked by tests/test_similarity.py).
_PLACEHOLDERS = {"project_name": "pkg", "package_name": "pkg", "package_description": "description",
                 "maintainer_name": "name", "maintainer_email": "name@example.com", "package_license": "license",
                 "package_format": 3, "library_name": "lib", "class_name": "Lib"}
#: Per build type: (buildtool dependencies, test dependencies) as many as ros2pkg/verb/create.py gives
#: (their names do not matter: XML text is not a token).
_BUILD_TYPES = {"ament_python": (0, 4), "ament_cmake": (1, 2), "cmake": (0, 0)}
#: Build dependencies (``--dependencies``) rendered: 0 to this many, as their count shapes package.xml
#: and CMakeLists.txt.
_MAX_DEPENDENCIES = 4
#: Template -> file name where ros2pkg writes it under another name (ros2pkg/api/create.py).
_RENAMED = {"main.py": "sample_node.py", "init.py": "__init__.py"}
#: A package name no student uses, to see whether a template's tokens keep the package name.
_MARK = "ros2course_package_mark"


def _ros2pkg_resources():
    """(ros2pkg's template folder, where it was found) or (None, why there is none).

    ros2pkg (ros2cli: ``ros2pkg/ros2pkg/resource/<kind>/*.em``, the templates ``ros2 pkg create``
    expands in ``ros2pkg/ros2pkg/api/create.py``; pinned as ros2/ros2cli de6cd27, 0.32.2, in
    ``shared/ros-src/SOURCES.md``) is read where it is importable (a sourced ROS), else
    from the underlay ``ros2course env --build`` builds (:mod:`ros2course.ros.underlay`), with
    :mod:`importlib.resources`; the package is located but never executed.
    """
    try:
        spec = importlib.util.find_spec("ros2pkg")
    except (ImportError, ValueError):
        spec = None
    where = "ros2pkg (importable)"
    if spec is None:
        from ros2course.ros import underlay  # noqa: PLC0415 - start time: the ROS install only when ros2pkg is not importable

        built = underlay.current()
        if built is not None:
            spec = importlib.machinery.PathFinder.find_spec("ros2pkg", [str(built.site_packages)])
            where = f"ros2pkg of the course's underlay ({built.prefix})"
    if spec is None or not spec.submodule_search_locations:
        return None, "ros2pkg not found (no sourced ROS 2, no `ros2course env --build` underlay)"
    try:
        folder = importlib.resources.files(importlib.util.module_from_spec(spec)) / "resource"
    except Exception as exc:  # noqa: BLE001 - an odd install: say so, compare without
        return None, f"ros2pkg's templates not readable: {exc}"
    if not folder.is_dir():
        return None, f"ros2pkg has no template folder at {folder}"
    return folder, where


def _render(template: str, data: dict) -> str | None:
    """``template`` expanded by empy as ros2pkg's ``_expand_template`` does (empy 4 or 3), or None."""
    try:
        import em  # noqa: PLC0415 - ros2pkg's template engine
    except ImportError:
        return None
    out = io.StringIO()
    try:
        if hasattr(em, "Configuration"):  # empy 4; no stdout proxy (ros2pkg installs one, a library must not)
            config = em.Configuration(defaultStdout=out, rawErrors=True, useProxy=False)
            interpreter = em.Interpreter(config=config, dispatcher=False, globals=dict(data))
        else:  # empy 3
            interpreter = em.Interpreter(output=out, options={em.BUFFERED_OPT: True, em.RAW_OPT: True},
                                         globals=dict(data))
        try:
            interpreter.string(template)
        finally:
            interpreter.shutdown()
    except Exception:  # noqa: BLE001 - a template this empy cannot expand is left out
        return None
    return out.getvalue()


def _variants(text: str) -> Iterator[dict]:
    """The data ``ros2 pkg create`` may expand ``text`` with: only the options the template reads vary."""
    nodes = (None, "node") if "node_name" in text else (None,)
    libraries = (None, "lib") if "cpp_library_name" in text else (None,)
    counts = range(_MAX_DEPENDENCIES + 1) if "dependencies" in text else (0,)
    kinds = list(_BUILD_TYPES) if "buildtool_dependencies" in text or "exports" in text else ["ament_python"]
    for node, library, count, kind in itertools.product(nodes, libraries, counts, kinds):
        tools, tests = _BUILD_TYPES[kind]
        yield dict(_PLACEHOLDERS, node_name=node, cpp_node_name=node, cpp_library_name=library,
                   dependencies=[f"dep{i}" for i in range(count)],
                   buildtool_dependencies=[f"tool{i}" for i in range(tools)],
                   test_dependencies=[f"test{i}" for i in range(tests)],
                   exports=[types.SimpleNamespace(tagname="build_type", content=kind)])


@functools.lru_cache(maxsize=1)
def _templates() -> tuple[tuple[tuple[str, str], ...], str]:
    """(((``<kind>/<file name>``, template text), ...), where from) of ros2pkg's templates of compared files."""
    folder, where = _ros2pkg_resources()
    if folder is None:
        return (), where
    found = []
    for kind in sorted(folder.iterdir(), key=lambda entry: entry.name):
        if not kind.is_dir():
            continue
        for template in sorted(kind.iterdir(), key=lambda entry: entry.name):
            name = _RENAMED.get(template.name[:-3], template.name[:-3])
            if template.name.endswith(".em") and (_wanted(name, 0) or name == "CMakeLists.txt"):
                found.append((f"{kind.name}/{name}", template.read_text(encoding="utf-8")))
    return tuple(found), where


@functools.lru_cache(maxsize=1024)
def _rendered(package: str, only_named: bool = False) -> tuple[tuple[str, str], ...]:
    """(file name, text) of every variant of every template (:func:`_variants`) for package ``package``,
    deduplicated; with ``only_named`` just those whose tokens name the package (:func:`_named`)."""
    out: dict[tuple[str, str], None] = {}
    for name, text in _templates()[0]:
        if only_named and not _named(name, text):
            continue
        for data in _variants(text):
            rendered = _render(text, dict(data, project_name=package, package_name=package))
            if rendered is not None:
                out.setdefault((name, rendered))
    return tuple(out)


@functools.lru_cache(maxsize=64)
def _named(name: str, template: str) -> bool:
    """Whether the package name survives copydetect's tokens in ``template`` (a C++ ``namespace <package>``:
    Pygments' Name.Namespace is not one copydetect turns into ``V``). Those are rendered per student."""
    from copydetect.utils import filter_code  # noqa: PLC0415 - slow to import

    for data in itertools.islice(_variants(template), 1):
        rendered = _render(template, dict(data, project_name=_MARK, package_name=_MARK))
        language = _language(name)
        if rendered is not None and language is not None:
            filtered = filter_code(rendered, name, language)[0]
            return _MARK in filtered.lower()
    return False


def generated_files() -> tuple[tuple[tuple[str, str], ...], str]:
    """((``<kind>/<file name>``, text) of every file ``ros2 pkg create`` can write, rendered, ...), where from).

    Every ``*.em`` template of ros2pkg (``ros2pkg/resource/{ament_python,ament_cmake,cmake,cpp,
    package_environment}``, expanded by ``ros2pkg/api/create.py``) rendered for each variant the command
    has: with and without ``--node-name`` and ``--library-name``, 0 to :data:`_MAX_DEPENDENCIES`
    ``--dependencies``, each build type's package.xml. Names are placeholders: copydetect's tokens do not
    see them, except where :func:`_named` says so (those are also rendered with each student's package
    name, :func:`_package_kgrams`). Templates of files never compared (``*.cmake.in``, the resource
    marker) are skipped. Nothing of ros2pkg is copied into this repository: its files are read at run time.

    Fallback: without ros2pkg (or without empy, its template engine) nothing is rendered and the second
    item says why; generated files are then left out only as code more than :func:`common_limit` students
    share (every student of a section has them, so in practice they still are).
    """
    templates, where = _templates()
    if not templates:
        return (), where
    rendered = _rendered(_PLACEHOLDERS["package_name"])
    if not rendered:
        return (), f"{where}: no template could be expanded (is empy installed?)"
    return rendered, where


#: package.xml's ``<name>`` (the package name ``ros2 pkg create`` was given).
_PACKAGE_NAME = re.compile(r"<name>\s*([A-Za-z0-9_]+)\s*</name>")


def _package_names(files: dict[str, str]) -> set[str]:
    """The package names of a submission: each package.xml's ``<name>`` and the folder holding it."""
    names = set()
    for rel, text in files.items():
        pure = PurePosixPath(rel)
        if pure.name == "package.xml":
            names.update(_PACKAGE_NAME.findall(text)[:1])
            if len(pure.parts) > 1:
                names.add(pure.parts[-2])
    return names


@functools.lru_cache(maxsize=1024)
def _package_kgrams(package: str) -> frozenset[int]:
    """k-grams of the templates whose tokens name the package (:func:`_named`), rendered for ``package``."""
    out: set[int] = set()
    for name, text in _rendered(package, only_named=True):
        out |= _kgrams(name, text)
    return frozenset(out)


@dataclasses.dataclass(frozen=True)
class _Boilerplate:
    hashes: frozenset[int]  # every k-gram hash of the boilerplate
    digests: frozenset[str]  # sha256 of each boilerplate file's normalised text (:func:`_digest`)
    files: int  # course files
    generated: int  # rendered templates
    generated_from: str


@functools.lru_cache(maxsize=4)
def _boilerplate(paths: tuple[Path, ...], generated: bool) -> _Boilerplate:
    """Boilerplate of the course files ``paths`` (folders or files), and of ``ros2 pkg create`` if ``generated``."""
    hashes: set[int] = set()
    digests: set[str] = set()
    count = 0
    for path in paths:
        files = _folder_files(path) if path.is_dir() else [(path.name, _decode(path.read_bytes()) or "")]
        for rel, text in files:
            count += 1
            digests.add(_digest(text))
            hashes |= _kgrams(rel, text)
    rendered, where = generated_files() if generated else ((), "not asked for")
    for name, text in rendered:
        hashes |= _kgrams(name, text)
    return _Boilerplate(frozenset(hashes), frozenset(digests), count, len(rendered), where)


def _digest(text: str) -> str:
    return hashlib.sha256("\n".join(line.rstrip() for line in text.strip().splitlines()).encode()).hexdigest()


def common_limit(students: int) -> int:
    """Code found in more than this many of a lesson's ``students`` submissions is common: ignored.

    Moss's ``-m`` ("the maximum number of times a given passage may appear before it is ignored",
    default 10): code much of the class shares, such as a listing everyone typed in or a hint from the
    lesson, is no evidence that two of them copied. Moss's fixed 10 never triggers in a lab section
    of five, so the limit scales with the section: a third of it, at least 2 and at most 10 (Moss's
    default), and never below a tenth of a large class:

    ``max(min(max(students // 3, 2), 10), students // 10)``: 2 for up to 8 students (code in 3 of a
    section of five is the section's, not a pair's), 5 for 15, 10 from 30 to 109, 30 for 300.

    Args:
        students: students of the lesson whose sources were found.
    """
    return max(min(max(students // 3, 2), 10), students // 10)


def compare_sources(lesson: str, sources: dict[str, dict[str, str]], boilerplate_paths: list[Path],
                    threshold: float = THRESHOLD, *, generated: bool = True,
                    min_shared: int = MIN_SHARED_TOKENS) -> tuple[list[SimilarPair], int, _Boilerplate]:
    """Pairs of students at least ``threshold`` alike beyond boilerplate, most alike first.

    Args:
        lesson: the lesson id (copied into each pair).
        sources: student id -> (relative path -> text), as :func:`read_sources` gives.
        boilerplate_paths: folders or files of code everyone was given (their k-grams are left out).
        threshold: the similarity (0..1) from which a pair is flagged.
        generated: also leave out what ``ros2 pkg create`` writes (:func:`generated_files`).
        min_shared: flag only pairs sharing at least this many tokens beyond boilerplate and common code
            (:data:`MIN_SHARED_TOKENS`).

    Returns:
        (pairs, files compared, the boilerplate used).
    """
    compare_files = _copydetect().compare_files

    boilerplate = _boilerplate(tuple(boilerplate_paths), generated)
    drop = boilerplate.hashes
    if generated and boilerplate.generated:  # templates naming the package, rendered with the students' names
        suffixes = {PurePosixPath(name).suffix for name, text in _templates()[0] if _named(name, text)}
        named = [_package_kgrams(name) for files in sources.values()
                 if any(PurePosixPath(rel).suffix in suffixes for rel in files)
                 for name in sorted(_package_names(files))]
        drop = drop.union(*named) if any(named) else drop
    prints = []  # (student, rel, fingerprint)
    seen: dict[tuple[str, str], object] = {}  # (suffix, digest) -> fingerprint: identical files tokenized once
    for student, files in sorted(sources.items()):
        for rel, text in files.items():
            digest = _digest(text)
            if digest in boilerplate.digests:  # a starter or reference file handed in unchanged
                continue
            key = (PurePosixPath(rel).name if PurePosixPath(rel).suffix == ".txt" else PurePosixPath(rel).suffix,
                   digest)
            if key not in seen:
                fingerprint = seen[key] = _fingerprint(rel, text)
                if fingerprint is not None:
                    _strip(fingerprint, drop)
            fingerprint = seen[key]
            if fingerprint is not None and len(fingerprint.hashes):
                prints.append((student, rel, fingerprint))
    # code more than common_limit students have (Moss's -m) is left out like boilerplate
    holders: dict[int, set[str]] = collections.defaultdict(set)
    for student, _rel, fingerprint in prints:
        for value in fingerprint.hashes:
            holders[int(value)].add(student)
    limit = common_limit(len(sources))
    common = {value for value, students in holders.items() if len(students) > limit}
    if common:
        for fingerprint in {id(fp): fp for _s, _r, fp in prints}.values():
            _strip(fingerprint, common)
        prints = [entry for entry in prints if len(entry[2].hashes)]
    hashes = [{int(value) for value in fingerprint.hashes} for _s, _r, fingerprint in prints]
    owners: dict[int, list[int]] = collections.defaultdict(list)
    for index, values in enumerate(hashes):
        for value in values:
            owners[value].append(index)
    shared: collections.Counter[tuple[int, int]] = collections.Counter()
    for files in owners.values():
        for a, b in itertools.combinations(files, 2):
            if prints[a][0] != prints[b][0] and PurePosixPath(prints[a][1]).suffix == PurePosixPath(prints[b][1]).suffix:
                shared[(a, b)] += 1
    best: dict[tuple[str, str], SimilarPair] = {}
    for (a, b), count in shared.items():
        (student_a, rel_a, fp_a), (student_b, rel_b, fp_b) = prints[a], prints[b]
        if count < threshold / 2 * min(len(hashes[a]), len(hashes[b])):
            continue
        overlap, (sim_a, sim_b), (slices_a, slices_b) = compare_files(fp_a, fp_b)
        score = (float(sim_a) + float(sim_b)) / 2
        key = (student_a, student_b)
        if score < threshold or int(overlap) < min_shared:
            continue
        if key not in best or (score, int(overlap)) > (best[key].score, best[key].shared_tokens):
            fragments = [(fp_a.raw_code[int(a0):int(a1)][:FRAGMENT_CHARS], fp_b.raw_code[int(b0):int(b1)][:FRAGMENT_CHARS])
                         for (a0, a1), (b0, b1) in itertools.islice(zip(zip(*slices_a), zip(*slices_b)), MAX_FRAGMENTS)]
            best[key] = SimilarPair(lesson, student_a, student_b, score, (rel_a, rel_b), fragments, int(overlap))
    pairs = sorted(best.values(), key=lambda pair: (-pair.score, -pair.shared_tokens, pair.first, pair.second))
    return pairs, len(prints), boilerplate


def find_sources(results: list[LessonResult], submissions: Path | None) -> dict[str, dict[str, Path]]:
    """lesson -> student -> the entry of that student's submission (folder or archive).

    Students with no entry in ``submissions`` (or ``submissions`` None) are left out.
    """
    by_lesson: dict[str, dict[str, Path]] = {}
    if submissions is None or not Path(submissions).is_dir():
        return by_lesson
    for result in results:
        entry = student_entry(Path(submissions), result.student) if result.student else None
        if entry is not None:
            by_lesson.setdefault(result.lesson, {})[result.student] = entry
    return by_lesson


def _lesson_paths(lesson_id: str) -> list[str]:
    from ros2course.lesson.catalog import load_catalog  # noqa: PLC0415 - start time: the catalog (yaml) only for a course's own files

    try:
        return list(load_catalog().get(lesson_id).workspace_paths)
    except Exception:  # noqa: BLE001 - an unknown lesson: compare every source file
        return []


def similar_pairs(results: list[LessonResult], submissions: Path | None, *, exclude_reference: bool = True,
                  threshold: float = THRESHOLD, generated: bool = True,
                  min_shared: int = MIN_SHARED_TOKENS) -> Comparison:
    """Similar pairs per lesson among the students of ``results`` (each lesson compared on its own).

    Args:
        results: the class's results (one per student and lesson).
        submissions: the submissions folder given to ``ros2course grade`` (folders and archives); None:
            nothing is compared.
        exclude_reference: also leave the reference solution (``solutions/``) out; the starter is always left out.
        threshold: flag pairs at least this alike (0..1), over the tokens left after boilerplate.
        generated: leave out what ``ros2 pkg create`` writes (:func:`generated_files`); False only to measure.
        min_shared: flag only pairs sharing at least this many tokens beyond boilerplate (:data:`MIN_SHARED_TOKENS`).

    Raises:
        ImportError: copydetect is not installed.
    """
    import time  # noqa: PLC0415 - only for this timing

    begin = time.perf_counter()
    by_lesson = find_sources(results, submissions)
    pairs: list[SimilarPair] = []
    files = boilerplate_count = generated_count = 0
    generated_from = ""
    students = {}
    for lesson, entries in sorted(by_lesson.items()):
        paths = _lesson_paths(lesson)
        sources = {student: read_sources(entry, paths) for student, entry in entries.items()}
        sources = {student: found for student, found in sources.items() if found}
        students[lesson] = len(sources)
        if len(sources) >= 2:
            found, counted, given = compare_sources(lesson, sources, boilerplate_folders(exclude_reference),
                                                    threshold, generated=generated, min_shared=min_shared)
            pairs += found
            files += counted
            boilerplate_count, generated_count, generated_from = given.files, given.generated, given.generated_from
    pairs.sort(key=lambda pair: (-pair.score, -pair.shared_tokens, pair.lesson, pair.first, pair.second))
    return Comparison(pairs, students, files, boilerplate_count, time.perf_counter() - begin, generated_count,
                      generated_from)
