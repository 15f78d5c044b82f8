"""ROS packages in a source folder, read from their ``package.xml`` with catkin_pkg.

catkin_pkg is the library colcon-ros itself uses to read manifests (REP 149,
format 3), so a package colcon sees is one these functions see. Used by the
build (which packages to build) and by the ROS install (which optional
components a workspace needs).
"""

from __future__ import annotations

from pathlib import Path

from catkin_pkg.package import InvalidPackage
from catkin_pkg.packages import find_packages as catkin_find

from ros2course.errors import NotGradable


def find_packages(src: Path) -> dict[str, tuple[Path, object]]:
    """Every ROS package under ``src``: name -> (folder, catkin_pkg Package).

    Raises:
        NotGradable: a ``package.xml`` that catkin_pkg cannot parse (its message included).
    """
    if not src.is_dir():
        return {}
    try:
        found = catkin_find(str(src))
    # catkin_pkg raises a bare ValueError for format="3a" and an AssertionError for format="-1"
    except (InvalidPackage, ValueError, AssertionError) as exc:
        detail = " ".join(line.strip() for line in str(exc).splitlines() if line.strip())
        raise NotGradable(f"a package.xml under {src} is invalid: {detail[:400]}",
                          "fix package.xml (format 3; name, version, description, maintainer with a valid email, license)") from exc
    return {pkg.name: (src / rel, pkg) for rel, pkg in found.items()}


def dependency_closure(packages: list[str], found: dict[str, tuple[Path, object]]) -> list[str]:
    """``packages`` plus every workspace package they depend on, recursively (sorted)."""
    todo = list(packages)
    seen: set[str] = set()
    while todo:
        name = todo.pop()
        if name in seen or name not in found:
            continue
        seen.add(name)
        pkg = found[name][1]
        for dep in (*pkg.build_depends, *pkg.buildtool_depends, *pkg.exec_depends, *pkg.build_export_depends):
            if dep.name in found:
                todo.append(dep.name)
    return sorted(seen)
