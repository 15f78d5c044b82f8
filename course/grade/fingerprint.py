"""A lesson's grader fingerprint: what a recorded grader-strength figure was measured on (issue 37).

A mutation score says how many wrong versions of the reference a grader catches. It stays
true only while the grader, what it stands on and what it is measured against are the same.
The fingerprint is one sha256 over the contents of:

* the lesson's grader module and every course module it imports (``graders/_*.py``, another
  lesson's grader), transitively, and the grader's data folder (``graders/data/<grader>/``);
* the engine code a grader runs on: the modules of the kit (``ros2course.kit``), the grading
  session and engine (``ros2course.grade``'s ``engine``, ``session``, ``verdicts``, ``observer``, ``machine``,
  ``checklist``, ``results``) and
  the runtime (``ros2course.run``) that the grader's imports and the grading engine's reach,
  transitively (:func:`engine_modules`): a kit step only another lesson's grader imports is not
  part of this lesson's fingerprint, so adding one leaves this lesson's figures current;
* the lesson's ``lesson.yaml``;
* the reference files the mutants are made from (the lesson's packages, their dependencies in
  ``solutions/src`` and its ``folders``: what :func:`ros2course.builder.reference.reference_workspace`
  copies).

A row of docs/grader-strength.md or a ``dev validate`` line measured under another fingerprint
is stale: it says so, with the date of its run.
"""

from __future__ import annotations

import ast
import hashlib
from collections.abc import Callable
from pathlib import Path

from ros2course.lesson.catalog import Lesson
from ros2course.ros.manifests import dependency_closure, find_packages

#: The engine's folder in the repository (``course/``, imported as ``ros2course``): engine files are named by
#: their path there in a fingerprint, wherever the engine is installed.
ENGINE_FOLDER = "course"

#: The engine modules (relative to the ``ros2course`` package) whose code every grader runs on.
ENGINE_PARTS = ("kit", "run", "grade/engine.py", "grade/session.py", "grade/verdicts.py", "grade/observer.py",
                "grade/machine.py", "grade/checklist.py", "grade/results.py")


def _files(root: Path) -> list[Path]:
    if root.is_file():
        return [root]
    return sorted(p for p in root.rglob("*")
                  if p.is_file() and not any(part == "__pycache__" or part.endswith(".egg-info")
                                             for part in p.relative_to(root).parts))


def _course_imports(module: Path, graders: Path) -> list[Path]:
    """The modules of the course's ``graders`` package that ``module`` imports (``from . import _x``,
    ``from ._x import y``, ``from .other_lesson import z``)."""
    try:
        tree = ast.parse(module.read_text(encoding="utf-8"))
    except (OSError, SyntaxError, ValueError):
        return []
    out = []
    here = module.parent if module.parent.is_relative_to(graders) else graders
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            if node.module:  # from .x import y, from .parent.x import y (a merged course's extended graders)
                parts = node.module.split(".")
                out += [here.joinpath(*parts[:-1], f"{parts[-1]}.py"), here.joinpath(*parts, "__init__.py")]
                out += [here.joinpath(*parts, f"{alias.name}.py") for alias in node.names]
            else:
                out += [here / f"{alias.name}.py" for alias in node.names]
    return [path for path in out if path.is_file()]


def _module_file(engine: Path, dotted: str) -> Path | None:
    """The file of engine module ``ros2course.a.b`` (``a/b.py`` or ``a/b/__init__.py``), None if not one."""
    parts = dotted.split(".")[1:]
    base = engine.joinpath(*parts) if parts else engine
    for candidate in (base.with_suffix(".py") if parts else None, base / "__init__.py"):
        if candidate is not None and candidate.is_file():
            return candidate
    return None


_IMPORTS: dict[tuple[str, int, int, str], list[Path]] = {}


def _engine_imports(module: Path, engine: Path) -> list[Path]:
    """The ``ros2course`` modules ``module`` imports anywhere in its code (function-level imports too), with the
    packages they sit in (importing ``ros2course.kit.scripts`` runs ``ros2course/kit/__init__.py``), and the
    submodules a ``from ros2course.kit import scripts`` names. Remembered per (path, mtime in ns, size), as
    :func:`_file_digest` is: every lesson's fingerprint walks the same engine modules (the strength doc parsed
    each about 140 times, 50 s of its 60)."""
    try:
        stat = module.stat()
    except OSError:
        return []
    key = (str(module), stat.st_mtime_ns, stat.st_size, str(engine))
    if key not in _IMPORTS:
        _IMPORTS[key] = _read_engine_imports(module, engine)
    return list(_IMPORTS[key])


def _read_engine_imports(module: Path, engine: Path) -> list[Path]:
    """:func:`_engine_imports`, read from the file."""
    try:
        tree = ast.parse(module.read_text(encoding="utf-8"))
    except (OSError, SyntaxError, ValueError):
        return []
    names: list[str] = []
    package = None
    if module.resolve().is_relative_to(engine):
        rel = module.resolve().relative_to(engine).with_suffix("").parts
        package = ["ros2course", *rel[:-1]] if rel[-1] != "__init__" else ["ros2course", *rel[:-1]]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                if package is None or node.level > len(package):
                    continue
                base = package[:len(package) - node.level + 1]
                dotted = ".".join(base + ([node.module] if node.module else []))
            else:
                dotted = node.module or ""
            names.append(dotted)
            names += [f"{dotted}.{alias.name}" for alias in node.names]
    out = []
    for dotted in names:
        if dotted != "ros2course" and not dotted.startswith("ros2course."):
            continue
        parts = dotted.split(".")
        for end in range(1, len(parts) + 1):  # the packages on the way, then the module itself
            found = _module_file(engine, ".".join(parts[:end]))
            if found is not None:
                out.append(found)
    return out


def _closure(start: list[Path], imports: Callable[[Path], list[Path]]) -> set[Path]:
    """The module files reachable from ``start`` through ``imports`` (module file -> the files it imports),
    each once; a path that is not a file is left out."""
    todo, seen = list(start), set()
    while todo:
        module = todo.pop()
        if module in seen or not module.is_file():
            continue
        seen.add(module)
        todo += imports(module)
    return seen


def engine_modules(course_modules: list[Path]) -> list[Path]:
    """The engine files (under :data:`ENGINE_PARTS`) a grader runs on: every ``ros2course`` module that
    ``course_modules`` (the grader and the course modules it imports) or the grading engine
    (``ros2course.grade.engine``, which loads and runs every grader) import, transitively, read from their
    code (:mod:`ast`, never imported). A module reached only through modules outside ENGINE_PARTS counts
    too: the walk goes through every ``ros2course`` module, and only the files hashed are filtered."""
    import ros2course  # noqa: PLC0415 - the engine's own folder

    engine = Path(ros2course.__file__).resolve().parent
    seen = _closure([*course_modules, engine / "grade" / "engine.py"], lambda module: _engine_imports(module, engine))
    parts = [engine / part for part in ENGINE_PARTS]
    return sorted(p for p in seen if p.resolve().is_relative_to(engine)
                  and any(p == part or p.is_relative_to(part) for part in parts))


def grader_files(lesson: Lesson) -> list[Path]:
    """Every file :func:`grader_fingerprint` covers for ``lesson``, sorted, each once."""
    root = lesson.course.root
    graders = lesson.course.graders
    modules = _closure([graders / f"{lesson.grader}.py"], lambda module: _course_imports(module, graders))
    files = set(modules)
    files.update(_files(graders / "data" / lesson.grader) if (graders / "data" / lesson.grader).is_dir() else [])
    files.update(engine_modules(sorted(modules)))
    if (lesson.folder / "lesson.yaml").is_file():
        files.add(lesson.folder / "lesson.yaml")
    solutions = root / "solutions"
    found = find_packages(solutions / "src")
    for name in dependency_closure(list(lesson.packages), found):
        files.update(_files(found[name][0]))
    for folder in lesson.folders:
        if (solutions / folder).exists():
            files.update(_files(solutions / folder))
    return sorted(files)


_DIGESTS: dict[tuple[str, int, int], bytes] = {}


def _file_digest(path: Path) -> bytes:
    """sha256 of ``path``'s bytes, remembered per (path, mtime in ns, size): the engine's modules are shared
    by every lesson, and the strength doc asks for each lesson's fingerprint more than once."""
    stat = path.stat()
    key = (str(path), stat.st_mtime_ns, stat.st_size)
    if key not in _DIGESTS:
        _DIGESTS[key] = hashlib.sha256(path.read_bytes()).digest()
    return _DIGESTS[key]


def grader_fingerprint(lesson: Lesson) -> str:
    """sha256 (hex, first 16 digits) over the paths and contents of :func:`grader_files`: equal only when
    the grader, the engine it runs on, the lesson and its reference are the same, wherever they are installed.

    A course file is named by its path in the course; an engine file by its path in the repository
    (``course/kit/checks.py``), whether the engine is the checkout's (an editable install, inside the
    bundled course's root) or an installed copy (a wheel, a course in another folder): one engine, one name.
    """
    return _fingerprint(lesson, with_engine=True)


def course_fingerprint(lesson: Lesson) -> str:
    """The part of :func:`grader_fingerprint` that is the course's own: the same digest over the lesson's
    files only (grader and course modules, data, lesson.yaml, reference), the engine left out.

    Recorded beside the grader fingerprint with every measurement, it tells two kinds of change apart
    afterwards: a grader fingerprint that changed while this one did not means only the engine changed
    under the lesson, nothing of the lesson was changed after its survivors were seen (issue 37: whether an
    earlier held-out sample may be graded again and still count as held out)."""
    return _fingerprint(lesson, with_engine=False)


def measurement(lesson: Lesson) -> dict[str, str]:
    """What a figure is recorded with: ``{"date": today (ISO), "fingerprint": ..., "course_fingerprint": ...}``."""
    import datetime as dt  # noqa: PLC0415 - only the author tools record measurements

    files = grader_files(lesson)  # found once: both digests are over the same walk of the grader's imports
    return {"date": dt.date.today().isoformat(), "fingerprint": _fingerprint(lesson, True, files),
            "course_fingerprint": _fingerprint(lesson, False, files)}


def _fingerprint(lesson: Lesson, with_engine: bool, files: list[Path] | None = None) -> str:
    """The digest over ``files`` (default :func:`grader_files` of ``lesson``), the engine's left out unless
    ``with_engine``."""
    import ros2course  # noqa: PLC0415 - the engine's own folder

    engine = Path(ros2course.__file__).resolve().parent
    root = lesson.course.root
    named = []
    for path in (grader_files(lesson) if files is None else files):
        where = path.resolve()
        if where.is_relative_to(engine) and not with_engine:
            continue
        named.append((f"{ENGINE_FOLDER}/{where.relative_to(engine).as_posix()}" if where.is_relative_to(engine)
                      else where.relative_to(root).as_posix() if where.is_relative_to(root) else path.name, path))
    digest = hashlib.sha256()
    for rel, path in sorted(named):  # in the order of their names, not of where they are installed
        digest.update(f"{rel}\0".encode())
        digest.update(_file_digest(path))
    return digest.hexdigest()[:16]
