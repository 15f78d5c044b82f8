"""Starter files: copied into the learner's workspace without ever overwriting theirs."""

from __future__ import annotations

import datetime as dt
import shutil
from pathlib import Path

from ros2course.lesson.catalog import Lesson


def starter_sources(lesson: Lesson) -> dict[Path, Path]:
    """Workspace-relative path -> the file it is copied from, over every starter layer.

    Layers, lowest first: the finished packages of ``starter_solutions`` (from
    ``solutions/``), then :attr:`ros2course.lesson.catalog.Lesson.starter_layers`: the
    starters of ``starter_includes``, the lesson's own last (a later layer's
    file wins on the same path).
    """
    solutions = lesson.course.solutions
    trees = [(solutions, solutions / folder) for folder in lesson.starter_solutions]
    trees += [(root, root) for root in lesson.starter_layers]
    sources: dict[Path, Path] = {}
    for base, tree in trees:
        if tree.is_file():
            sources[tree.relative_to(base)] = tree
        elif tree.is_dir():
            for path in tree.rglob("*"):
                if path.is_file() and not any(part == "__pycache__" or part.endswith(".egg-info")
                                              for part in path.relative_to(tree).parts):
                    sources[path.relative_to(base)] = path
    return dict(sorted(sources.items()))


def starter_files(lesson: Lesson) -> list[Path]:
    """The lesson's starter files, workspace-relative (sorted)."""
    return list(starter_sources(lesson))


def copy_starter(lesson: Lesson, workspace_root: Path) -> tuple[list[Path], list[Path]]:
    """Copy every starter file that does not exist yet in the workspace.

    Returns:
        ``(copied, kept)``: workspace-relative paths created, and paths the
        learner already had (left untouched: a conflict, listed to the learner).
    """
    copied, kept = [], []
    for rel, source in starter_sources(lesson).items():
        target = workspace_root / rel
        if target.exists() or target.is_symlink():
            kept.append(rel)
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, target)
        copied.append(rel)
    return copied, kept


def reset_starter(lesson: Lesson, workspace_root: Path, backups_root: Path) -> tuple[Path | None, list[Path]]:
    """Back up the learner's versions of the starter files, then restore the starter ones.

    Returns:
        ``(backup_folder or None if nothing needed backing up, restored paths)``.
    """
    stamp = dt.datetime.now().strftime("%Y-%m-%d_%H-%M-%S-%f")
    backup = backups_root / lesson.id / stamp
    used_backup = False
    restored = []
    for rel, source in starter_sources(lesson).items():
        target = workspace_root / rel
        if target.exists():
            if target.read_bytes() == source.read_bytes():
                continue
            (backup / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(target, backup / rel)  # copy first: the learner's file is safe before we touch it
            used_backup = True
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, target)
        restored.append(rel)
    return (backup if used_backup else None), restored
