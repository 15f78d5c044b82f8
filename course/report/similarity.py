"""Similar submissions of a batch-graded class (issue 21), with ``copydetect``.

Each student's source files for a lesson are fingerprinted with copydetect's winnowing
(:class:`copydetect.CodeFingerprint`: Pygments tokens, names and literals normalised, so
renaming a variable does not hide a copy). Code every student was given is *boilerplate*:
its fingerprints are removed before comparing, and a file handed in unchanged is not compared
at all. That is every lesson's starter files (and the ``solutions/`` files starters offer
whole) always, and the reference solutions (``solutions/``, the tutorial's listings the
learner is told to type in) unless ``exclude_reference=False``. A fingerprint found
in the submissions of more than :func:`common_limit` students does not make a pair a
candidate (Moss's ``-m``: code much of the class shares, such as a tutorial listing everyone
typed in, is no evidence of copying).

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
import io
import itertools
import tarfile
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


@dataclasses.dataclass
class SimilarPair:
    """Two students whose submissions for ``lesson`` are alike.

    Attributes:
        lesson: the lesson id.
        first, second: the student ids.
        score: similarity 0..1: the mean of copydetect's two directions (copied tokens / compared
            tokens of each file) over the pair's most alike files.
        files: (first's file, second's file), paths relative to the submission.
        fragments: (text in first's file, text in second's file) of the matching code, at most
            :data:`MAX_FRAGMENTS` of :data:`FRAGMENT_CHARS` characters.
    """

    lesson: str
    first: str
    second: str
    score: float
    files: tuple[str, str]
    fragments: list[tuple[str, str]]


@dataclasses.dataclass
class Comparison:
    """What :func:`similar_pairs` compared and found.

    Attributes:
        pairs: flagged pairs, most alike first.
        students: lesson id -> number of students whose sources were found.
        files: source files fingerprinted (boilerplate included).
        boilerplate_files: files whose fingerprints were left out (starter, reference).
        seconds: wall time, seconds.
    """

    pairs: list[SimilarPair]
    students: dict[str, int]
    files: int
    boilerplate_files: int
    seconds: float


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
    from ros2course.lesson import content_root  # noqa: PLC0415
    from ros2course.lesson.catalog import load_catalog  # noqa: PLC0415

    solutions = content_root() / "solutions"
    out: list[Path] = []
    for lesson in load_catalog().lessons:
        out += [*lesson.starter_layers, *(solutions / rel for rel in lesson.starter_solutions)]
    if exclude_reference:
        out = [path for path in out if not path.is_relative_to(solutions)] + [solutions]
    return sorted({path for path in out if path.exists()})


#: Pygments lexer per suffix (naming it skips Pygments' search by file name, most of a fingerprint's cost);
#: files of other suffixes (.msg, .srv, a .txt that is not CMakeLists.txt) are compared untokenized.
LEXERS = {".py": "python", ".cpp": "cpp", ".hpp": "cpp", ".h": "cpp", ".cc": "cpp", ".c": "c", ".xml": "xml",
          ".launch": "xml", ".yaml": "yaml", ".yml": "yaml", ".sh": "bash", ".cfg": "ini", ".toml": "toml"}


def _fingerprint(rel: str, text: str, boilerplate):
    from copydetect import CodeFingerprint  # noqa: PLC0415 - slow to import

    pure = PurePosixPath(rel)
    language = "cmake" if pure.name == "CMakeLists.txt" else LEXERS.get(pure.suffix)
    try:
        return CodeFingerprint(rel, _NOISE, _GUARANTEE, boilerplate=boilerplate, fp=io.StringIO(text),
                               filter=language is not None, language=language)
    except Exception:  # noqa: BLE001 - a file Pygments cannot tokenize is simply not compared
        return None


@functools.lru_cache(maxsize=2)
def _boilerplate(paths: tuple[Path, ...]) -> tuple[list[int], frozenset[str], int]:
    """(fingerprints, sha256 of the normalised texts, file count) of the boilerplate."""
    hashes: set[int] = set()
    digests: set[str] = set()
    count = 0
    for path in paths:
        files = _folder_files(path) if path.is_dir() else [(path.name, _decode(path.read_bytes()) or "")]
        for rel, text in files:
            count += 1
            digests.add(_digest(text))
            fingerprint = _fingerprint(rel, text, None)
            if fingerprint is not None:
                hashes.update(int(h) for h in fingerprint.hashes)
    return sorted(hashes), frozenset(digests), count


def _digest(text: str) -> str:
    return hashlib.sha256("\n".join(line.rstrip() for line in text.strip().splitlines()).encode()).hexdigest()


def common_limit(students: int) -> int:
    """Fingerprints shared by more than this many of ``students`` submissions count as boilerplate."""
    return max(10, students // 10)


def compare_sources(lesson: str, sources: dict[str, dict[str, str]], boilerplate_paths: list[Path],
                    threshold: float = THRESHOLD) -> tuple[list[SimilarPair], int, int]:
    """Pairs of students at least ``threshold`` alike, most alike first.

    Args:
        lesson: the lesson id (copied into each pair).
        sources: student id -> (relative path -> text), as :func:`read_sources` gives.
        boilerplate_paths: folders or files of code everyone was given (matches there do not count).
        threshold: the similarity (0..1) from which a pair is flagged.

    Returns:
        (pairs, files fingerprinted, boilerplate files).
    """
    from copydetect import compare_files  # noqa: PLC0415 - slow to import

    boilerplate, given, boilerplate_count = _boilerplate(tuple(boilerplate_paths))
    prints = []  # (student, rel, fingerprint, hashes)
    seen: dict[tuple[str, str], object] = {}  # (suffix, digest) -> fingerprint: identical files tokenized once
    for student, files in sorted(sources.items()):
        for rel, text in files.items():
            digest = _digest(text)
            if digest in given:  # a starter or reference file handed in unchanged
                continue
            key = (PurePosixPath(rel).name if PurePosixPath(rel).suffix == ".txt" else PurePosixPath(rel).suffix,
                   digest)
            if key not in seen:
                seen[key] = _fingerprint(rel, text, boilerplate)
            fingerprint = seen[key]
            if fingerprint is not None and len(fingerprint.hashes):
                prints.append((student, rel, fingerprint, {int(h) for h in fingerprint.hashes}))
    owners: dict[int, set[int]] = collections.defaultdict(set)
    for index, (_student, _rel, _fp, hashes) in enumerate(prints):
        for value in hashes:
            owners[value].add(index)
    limit = common_limit(len(sources))
    shared: collections.Counter[tuple[int, int]] = collections.Counter()
    for files in owners.values():
        if len(files) < 2 or len({prints[i][0] for i in files}) > limit:
            continue
        for a, b in itertools.combinations(sorted(files), 2):
            if prints[a][0] != prints[b][0] and PurePosixPath(prints[a][1]).suffix == PurePosixPath(prints[b][1]).suffix:
                shared[(a, b)] += 1
    best: dict[tuple[str, str], SimilarPair] = {}
    for (a, b), count in shared.items():
        (student_a, rel_a, fp_a, hashes_a), (student_b, rel_b, fp_b, hashes_b) = prints[a], prints[b]
        if count < threshold / 2 * min(len(hashes_a), len(hashes_b)):
            continue
        _overlap, (sim_a, sim_b), (slices_a, slices_b) = compare_files(fp_a, fp_b)
        score = (float(sim_a) + float(sim_b)) / 2
        key = (student_a, student_b)
        if score >= threshold and (key not in best or score > best[key].score):
            fragments = [(fp_a.raw_code[int(a0):int(a1)][:FRAGMENT_CHARS], fp_b.raw_code[int(b0):int(b1)][:FRAGMENT_CHARS])
                         for (a0, a1), (b0, b1) in itertools.islice(zip(zip(*slices_a), zip(*slices_b)), MAX_FRAGMENTS)]
            best[key] = SimilarPair(lesson, student_a, student_b, score, (rel_a, rel_b), fragments)
    pairs = sorted(best.values(), key=lambda pair: (-pair.score, pair.first, pair.second))
    return pairs, len(prints), boilerplate_count


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
    from ros2course.lesson.catalog import load_catalog  # noqa: PLC0415

    try:
        return list(load_catalog().get(lesson_id).workspace_paths)
    except Exception:  # noqa: BLE001 - an unknown lesson: compare every source file
        return []


def similar_pairs(results: list[LessonResult], submissions: Path | None, *, exclude_reference: bool = True,
                  threshold: float = THRESHOLD) -> Comparison:
    """Similar pairs per lesson among the students of ``results`` (each lesson compared on its own).

    Args:
        results: the class's results (one per student and lesson).
        submissions: the submissions folder given to ``ros2course grade`` (folders and archives); None:
            nothing is compared.
        exclude_reference: also leave the reference solution (``solutions/``) out; the starter is always left out.
        threshold: flag pairs at least this alike (0..1).

    Raises:
        ImportError: copydetect is not installed.
    """
    import time  # noqa: PLC0415

    begin = time.perf_counter()
    by_lesson = find_sources(results, submissions)
    pairs: list[SimilarPair] = []
    files = boilerplate_count = 0
    students = {}
    for lesson, entries in sorted(by_lesson.items()):
        paths = _lesson_paths(lesson)
        sources = {student: read_sources(entry, paths) for student, entry in entries.items()}
        sources = {student: found for student, found in sources.items() if found}
        students[lesson] = len(sources)
        if len(sources) >= 2:
            found, counted, given = compare_sources(lesson, sources, boilerplate_folders(exclude_reference),
                                                    threshold)
            pairs += found
            files += counted
            boilerplate_count = given
    pairs.sort(key=lambda pair: (-pair.score, pair.lesson, pair.first, pair.second))
    return Comparison(pairs, students, files, boilerplate_count, time.perf_counter() - begin)
