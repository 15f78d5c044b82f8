"""The course's own reference packages (``solutions/src``): copied into workspaces and built.

``dev validate`` grades copies of them (and of wrong solutions made from them);
batch grading builds the interface packages a lesson's grader imports from
them, so the grader never imports a submission's generated code
(:func:`trusted_interface_packages`).
"""

from __future__ import annotations

import dataclasses
import fcntl
import hashlib
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from ros2course.builder.colcon import COLCON_ARGS, build_packages
from ros2course.errors import CourseError, ValidationFailed
from ros2course.lesson import Course
from ros2course.lesson.catalog import Lesson
from ros2course.ros import env as env_mod
from ros2course.ros.manifests import Manifest, dependency_closure, find_packages


def solution_packages(course: Course) -> dict[str, tuple[Path, Manifest]]:
    """Every package under ``course``'s ``solutions/src``: name -> (folder, its
    :class:`~ros2course.ros.manifests.Manifest`)."""
    return find_packages(course.solutions / "src")


def reference_workspace(lesson: Lesson, dest: Path, packages: list[str] | None = None, *,
                        with_folders: bool = True, with_tests: bool = True) -> Path:
    """Copy reference packages from ``solutions/src`` into ``dest/src``, and the lesson's ``folders``.

    Args:
        packages: which ones (default: the lesson's packages and their dependencies).
        with_folders: also copy the lesson's non-ROS ``folders`` from ``solutions/`` (a case's
            workspace needs them; an underlay of dependencies does not).
        with_tests: also copy each package's own ``test/`` folder. A shared build
            (:func:`build_reference`) leaves them out: they are testing-your-nodes' answer, and batch
            grading shows its trusted build to the submission (nothing builds or grades with them).

    Raises:
        ValidationFailed: a folder the lesson names is not in ``solutions/``.
    """
    solutions = lesson.course.solutions
    found = solution_packages(lesson.course)
    (dest / "src").mkdir(parents=True, exist_ok=True)
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info")
    for name in (dependency_closure(lesson.packages, found) if packages is None else packages):
        package = found[name][0]

        def without_tests(folder: str, names: list[str], package: Path = package) -> set[str]:
            skip = set(ignore(folder, names))
            if Path(folder) == package and "test" in names:
                skip.add("test")
            return skip

        shutil.copytree(package, dest / "src" / package.name, ignore=ignore if with_tests else without_tests)
    for folder in lesson.folders if with_folders else ():
        if not (solutions / folder).is_dir():
            raise ValidationFailed(f"lesson {lesson.id} names folder {folder!r}, which is not in solutions/")
        shutil.copytree(solutions / folder, dest / folder, ignore=ignore, dirs_exist_ok=True)
    return dest


def lesson_dependencies(lesson: Lesson) -> list[str]:
    """Reference packages the lesson's packages depend on but does not itself teach (e.g. interfaces)."""
    return [name for name in dependency_closure(lesson.packages, solution_packages(lesson.course)) if name not in lesson.packages]


def trusted_interface_packages(lessons: list[Lesson]) -> list[str]:
    """The reference packages batch grading must build for ``lessons``' graders: their declared
    ``interfaces`` and ``references`` (lesson.yaml) and what those depend on in ``solutions/src``, sorted.

    Derived from what each grader imports, never from the lesson's own packages: a lesson that
    teaches ``package_with_interfaces`` and grades with its types still gets the course's copy.

    Raises:
        CourseError: a lesson declares an interface or reference package ``solutions/src`` does not have
            (the course is broken; no class can be graded on it), or ``lessons`` come from two courses.
    """
    courses = list(dict.fromkeys(lesson.course for lesson in lessons))
    if len(courses) > 1:  # one batch, one course: two courses' packages of one name would shadow each other
        raise CourseError(f"lessons of {len(courses)} courses in one batch ({', '.join(str(c.root) for c in courses)})",
                          "grade each course's lessons in a batch of their own")
    found = solution_packages(courses[0]) if courses else {}
    for lesson in lessons:
        unknown = [name for name in [*lesson.interfaces, *lesson.references] if name not in found]
        if unknown:
            raise CourseError(f"lesson {lesson.id} cannot be graded in batch: its grader reads the reference "
                              f"package {', '.join(unknown)}, and the course has no package of that name "
                              f"in {lesson.course.solutions / 'src'}",
                              "a fault of the course: add the package to solutions/src or fix 'interfaces:' "
                              "or 'references:' in lesson.yaml")
    return dependency_closure(list(dict.fromkeys(p for lesson in lessons for p in [*lesson.interfaces,
                                                                                 *lesson.references])), found)


def build_reference(lesson: Lesson, dest: Path, packages: list[str], log_name: str) -> Path:
    """Copy ``packages`` from ``solutions/src`` into ``dest`` and build them with colcon.

    Returns:
        ``dest`` (its ``install/`` is the build).

    Raises:
        CourseError: they do not build (a fault of the course or the machine), the excerpt of the build log
            in the message.
    """
    reference_workspace(lesson, dest, packages, with_folders=False, with_tests=False)
    env = env_mod.activate()
    built = build_packages(dest, packages, env, dest / "log" / log_name)
    if not built.ok:
        raise CourseError(f"the course's own packages {', '.join(packages)} do not build:\n{built.excerpt}",
                          f"run ros2course doctor; see {built.log_path}")
    return dest


#: Builds of reference packages (interfaces) unused for this long are deleted, seconds.
CACHE_MAX_AGE = 14 * 24 * 3600.0
_COMPLETE = ".ros2course-complete"


@dataclasses.dataclass(frozen=True)
class ReferenceBuild:
    """A built workspace of reference packages (:func:`shared_reference_build`).

    Attributes:
        path: the workspace (``install/`` inside), readable by every user (batch grading sources its
            ``setup.bash`` as the submission's uid).
        temporary: True when it was built for this caller only (no writable cache): :meth:`discard` removes it.
    """

    path: Path
    temporary: bool

    def discard(self) -> None:
        """Remove the build if it was made for this caller only; a shared (cached) build stays."""
        if self.temporary:
            shutil.rmtree(self.path.parent, ignore_errors=True)


def reference_cache_folder() -> Path:
    """Where shared reference builds live, whether or not it exists: ``<sys.prefix>/var/cache/ros2course/reference``
    (batch grading hides it from submissions, :func:`ros2course.batch.runner.default_hidden`)."""
    return Path(sys.prefix) / "var" / "cache" / "ros2course" / "reference"


def reference_cache_root() -> Path | None:
    """Where shared reference builds live (:func:`reference_cache_folder`), made if missing: next to the
    ROS install they were built against (so a new venv never reads an old build, and every uid can read it,
    unlike ``~/.cache`` under a 0700 home). None when that folder cannot be written."""
    root = reference_cache_folder()
    try:
        root.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    if not os.access(root, os.W_OK) or root.stat().st_uid != os.geteuid() or root.stat().st_mode & 0o022:
        return None  # someone else's folder, or writable by others: never build trusted code there
    return root


def _cache_key(course: Course, packages: list[str], env: dict[str, str]) -> str:
    """Hash of the packages' file contents (``course``'s reference packages) and of the ROS install they
    build against."""
    found = solution_packages(course)
    digest = hashlib.sha256()
    for name in sorted(packages):
        folder = found[name][0]
        for path in sorted(p for p in folder.rglob("*") if p.is_file() and "__pycache__" not in p.parts):
            digest.update(f"{name}/{path.relative_to(folder)}\0".encode() + path.read_bytes() + b"\0")
    # "without test/": builds made before shared builds left out the packages' tests are never reused
    digest.update(f"{sys.executable}\0{sys.version}\0{COLCON_ARGS}\0without test/\0".encode())
    for prefix in env.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        index = Path(prefix) / "share" / "ament_index" / "resource_index" / "packages"
        try:
            digest.update(f"{prefix}\0{index.stat().st_mtime_ns}\n".encode())
        except OSError:
            digest.update(f"{prefix}\0-\n".encode())
    return digest.hexdigest()[:24]


def shared_reference_build(lesson: Lesson, packages: list[str], log_name: str = "build.log") -> ReferenceBuild:
    """``packages`` from ``solutions/src`` built once and shared until their files or the ROS install change.

    ``dev validate``'s underlay and batch grading's trusted interfaces are the same reference
    packages built the same way; building ``package_with_interfaces`` (rosidl: C, C++ and Python
    code, ~40 s on 2 cores) once per change instead of once per lesson or per class makes both
    faster. The build goes straight to its final folder (colcon and CMake write absolute paths) under
    an exclusive lock, and counts only once it is marked complete; a failed build is removed.

    Args:
        lesson: the lesson asking (for error messages and :func:`reference_workspace`).
        packages: reference package names (with their dependencies among them).
        log_name: name of the colcon log inside ``<build>/log``.

    Raises:
        CourseError: the packages do not build (a fault of the course or machine).
    """
    env = env_mod.activate()
    root = reference_cache_root()
    if root is None:
        dest = Path(tempfile.mkdtemp(prefix="ros2course-reference-")) / "ws"
        dest.parent.chmod(0o755)
        try:
            return ReferenceBuild(build_reference(lesson, dest, packages, log_name), temporary=True)
        except BaseException:
            shutil.rmtree(dest.parent, ignore_errors=True)
            raise
    _prune(root)
    key = _cache_key(lesson.course, packages, env)
    folder = root / key
    with open(root / f"{key}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # another check or batch building the same packages: wait for it
        marker = folder / _COMPLETE
        if marker.is_file():
            marker.touch()
            return ReferenceBuild(folder / "ws", temporary=False)
        shutil.rmtree(folder, ignore_errors=True)  # a build that died half-way
        folder.mkdir(mode=0o755)
        try:
            build_reference(lesson, folder / "ws", packages, log_name)
        except BaseException:
            shutil.rmtree(folder, ignore_errors=True)
            raise
        marker.write_text(" ".join(packages) + "\n", encoding="utf-8")
        return ReferenceBuild(folder / "ws", temporary=False)


def _prune(root: Path) -> None:
    """Delete shared builds unused for :data:`CACHE_MAX_AGE` (never one another process holds locked)."""
    now = time.time()
    for marker in root.glob(f"*/{_COMPLETE}"):
        try:
            if now - marker.stat().st_mtime < CACHE_MAX_AGE:
                continue
        except OSError:
            continue
        folder = marker.parent
        with open(root / f"{folder.name}.lock", "w") as lock:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                continue
            shutil.rmtree(folder, ignore_errors=True)
