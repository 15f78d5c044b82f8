"""Kit steps that read a learner's package the way colcon and ament do (never by importing it)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ros2course.grade.checklist import Unmet
from ros2course.kit.session_protocol import Session
from ros2course.ros.manifests import find_packages


def source_package(s: Session, name: str) -> tuple[Any, Any] | None:
    """``(folder, catkin_pkg Package)`` of package ``name`` under the workspace's ``src/``, or None."""
    return find_packages(s.workspace_root / "src").get(name)


#: The dependency kinds of package.xml format 2/3 (REP 149), as catkin_pkg's Package lists them.
DEPENDENCY_KINDS = ("build", "build_export", "exec")


def declared_dependencies(package: Any, kinds: tuple[str, ...] = DEPENDENCY_KINDS) -> set[str]:
    """Names a ``package.xml`` lists as dependencies of ``kinds`` (``<depend>`` is all three: REP 149); by default
    any kind."""
    return {d.name for kind in kinds for d in getattr(package, f"{kind}_depends")}


def depends(s: Session, check_id: str, package: str, needed: tuple[str, ...] | list[str],
            kinds: tuple[str, ...] = ("exec",)) -> bool:
    """Record ``check_id`` on whether ``package``'s package.xml declares every name in ``needed`` as a dependency
    of each of ``kinds`` (default: run time, what ``ros2 run`` needs of a Python package; a C++ package also needs
    ``("build", "exec")``).

    Partial credit per name. The rule is the tutorial's (ch. 12.1, 15.1,
    18.1: ``ros2 pkg create --dependencies ...`` writes ``<depend>`` tags, every kind at once);
    without them ``colcon build --packages-up-to`` does not build the
    dependency first and rosdep cannot install it. A ``<build_depend>`` alone is not one ``ros2 run`` sees
    (audit of stop 71: print-forever-node's rclpy passed so).
    """
    expected = ", ".join(f"<depend>{n}</depend>" for n in needed) + " in package.xml"
    found = source_package(s, package)
    if found is None:
        return s.record(check_id, False, f"no package {package} in src/", expected)
    deps = declared_dependencies(found[1])
    missing = [n for n in needed if not all(n in declared_dependencies(found[1], (kind,)) for kind in kinds)]
    return s.record(check_id, not missing, f"package.xml dependencies: {', '.join(sorted(deps)) or 'none'}"
                    + (f" (missing {', '.join(missing)} as {' and '.join(kinds)} dependenc{'y' if len(missing) == 1 else 'ies'}: "
                       "<depend> is every kind)"
                       if missing else ""), expected,
                    fraction=(len(needed) - len(missing)) / len(needed))


def project_files(s: Session, check_id: str, project: Path, files: tuple[Path, ...] | list[Path]) -> Path:
    """Record ``check_id`` on whether the non-ROS project folder ``project`` holds every file in ``files``.

    Args:
        project: the folder, relative to the workspace (e.g. ``python/minimalist_package``).
        files: paths relative to ``project``.

    Returns:
        the folder's absolute path.

    Raises:
        Unmet: the folder does not exist (nothing else can be judged).
    """
    folder = s.workspace_root / project
    if not folder.is_dir():
        s.record(check_id, False, f"there is no folder {project}/ in the workspace", f"the project folder {project}/")
        raise Unmet(f"{project}/ does not exist")
    missing = [str(f) for f in files if not (folder / f).is_file()]
    s.record(check_id, not missing, "missing: " + ", ".join(missing) if missing else f"all {len(files)} files are there",
             ", ".join(str(f) for f in files) + f" under {project}/")
    return folder
