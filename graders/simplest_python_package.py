"""Grader for ``simplest-python-package`` (seed ch. 6-7; contract in shared/LESSONS.md).

The lesson is about packaging, so the grader reads the packaging files the contract
names (``package.xml``, ``setup.cfg``, ``resource/``) and, above all, judges what
``colcon build`` installed: the ament index entry ``ros2 pkg list`` reads, the installed
``package.xml``, and the Python package importable from the sourced workspace.
"""

from __future__ import annotations

from pathlib import Path

from ros2course import kit
from ros2course.kit import Check, Session, Unmet
from ros2course.kit.packaging import (
    ament_index_packages,
    data_files_mapping,
    install_prefix,
    installed_import,
    relative,
    setup_cfg_problems,
    setup_py_arguments,
    site_packages,
)

PACKAGE = "the_simplest_python_package"
INDEX = "share/ament_index/resource_index/packages"

#: No node is observed: the checks read the build and the installed files.
WINDOW = 0.0

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("package_xml", "package.xml is format 3 and names the package the_simplest_python_package", 2,
          "start package.xml with <package format=\"3\"> and set <name>the_simplest_python_package</name>"),
    Check("build_type", "package.xml exports build_type ament_python", 1,
          "add <export><build_type>ament_python</build_type></export> to package.xml"),
    Check("resource_file", "The marker file resource/the_simplest_python_package exists", 1,
          "create an empty file resource/the_simplest_python_package next to setup.py"),
    Check("ament_index", "setup.py installs the marker, so the ament index (ros2 pkg list) lists the package", 2,
          "in setup.py data_files: ('share/ament_index/resource_index/packages', ['resource/' + package_name])"),
    Check("package_xml_installed", "setup.py installs package.xml to share/the_simplest_python_package/", 1,
          "in setup.py data_files: ('share/' + package_name, ['package.xml'])"),
    Check("setup_cfg", "setup.cfg puts executables in lib/the_simplest_python_package", 1,
          "setup.cfg needs [develop] script_dir=$base/lib/the_simplest_python_package and "
          "[install] install_scripts=$base/lib/the_simplest_python_package"),
    Check("python_package", "The Python package the_simplest_python_package is installed and importable", 2,
          "create the_simplest_python_package/__init__.py (an empty file) and list it in setup.py with "
          "packages=find_packages(exclude=['test'])"),
]

#: what colcon-ros prints when setup.py leaves the marker or package.xml out of data_files
FALLBACK = ("colcon-ros added it through its implicit fallback (colcon warns \"doesn't explicitly install\"; "
            "that fallback will be removed)")


def _record_index(s: Session, prefix: Path, installs: dict[str, str], problem: str) -> None:
    """``ament_index``: setup.py installs the marker itself, and the sourced index lists the package."""
    wanted = f"{INDEX}/{PACKAGE}"
    explicit = [src for src, dest in installs.items() if dest == wanted]
    listed = ament_index_packages(s).get(PACKAGE)
    expected = f"setup.py data_files installs resource/{PACKAGE} to {INDEX}/, and the ament index lists {PACKAGE}"
    if listed is None:
        installed_marker = prefix / INDEX / PACKAGE
        there = sorted(p.name for p in (prefix / INDEX).iterdir()) if (prefix / INDEX).is_dir() else []
        s.record("ament_index", False, f"the sourced workspace does not list {PACKAGE}: no {relative(s, installed_marker)}"
                 + (f" (that folder holds: {', '.join(there)})" if there else ""), expected)
    elif problem:
        s.record("ament_index", False, problem, expected)
    elif not explicit:
        to_index = sorted(f"{src} -> {dest}" for src, dest in installs.items() if dest.startswith(INDEX))
        s.record("ament_index", False,
                 f"the index lists {PACKAGE}, but setup.py data_files does not install its marker"
                 + (f" (it installs {', '.join(to_index)})" if to_index else "") + f"; {FALLBACK}", expected)
    else:
        s.record("ament_index", True, f"data_files installs {explicit[0]}; the ament index lists {PACKAGE} "
                 f"(prefix {relative(s, Path(listed))})", expected)


def _record_manifest(s: Session, prefix: Path, installs: dict[str, str], problem: str) -> None:
    """``package_xml_installed``: setup.py installs package.xml to share/<package>/ and it is there."""
    manifest = prefix / "share" / PACKAGE / "package.xml"
    expected = f"setup.py data_files installs package.xml to share/{PACKAGE}/"
    if not manifest.is_file():
        s.record("package_xml_installed", False, f"{relative(s, manifest)} is missing", expected)
    elif problem:
        s.record("package_xml_installed", False, problem, expected)
    elif installs.get("package.xml") != f"share/{PACKAGE}/package.xml":
        where = installs.get("package.xml")
        s.record("package_xml_installed", False,
                 ("setup.py data_files does not install package.xml" if where is None
                  else f"setup.py data_files installs package.xml to {where}") + f"; {FALLBACK}", expected)
    else:
        s.record("package_xml_installed", True, f"{relative(s, manifest)} installed by data_files", expected)


def grade(s: Session) -> None:
    """Read the package's files, then look at the install tree and the sourced environment."""
    found = kit.source_package(s, PACKAGE)
    if found is None:  # the build step already insists on it; kept for direct calls
        raise Unmet(f"no package {PACKAGE} in src/")
    folder, pkg = found
    fmt = int(pkg.package_format)
    s.record("package_xml", fmt == 3 and folder.name == PACKAGE,
             f"{relative(s, folder / 'package.xml')}: format {fmt}, name {pkg.name}, folder {folder.name}",
             f"format 3, in the folder src/{PACKAGE}")
    build_type = pkg.get_build_type()
    s.record("build_type", build_type == "ament_python", f"build_type {build_type}", "build_type ament_python")
    marker = folder / "resource" / PACKAGE
    if marker.is_file():
        observed = f"{relative(s, marker)} exists"
    elif (folder / "resource").is_dir():
        others = sorted(p.name for p in (folder / "resource").iterdir())
        observed = f"no {relative(s, marker)}; resource/ holds: {', '.join(others) or 'nothing'}"
    else:
        observed = f"there is no resource/ folder in {relative(s, folder)}"
    s.record("resource_file", marker.is_file(), observed, f"a file resource/{PACKAGE} (empty)")

    arguments, problem = setup_py_arguments(s, folder)
    installs = data_files_mapping(arguments.get("data_files"))
    prefix = install_prefix(s, PACKAGE)
    _record_index(s, prefix, installs, problem)
    _record_manifest(s, prefix, installs, problem)

    problems = setup_cfg_problems(folder / "setup.cfg", PACKAGE)
    s.record("setup_cfg", not problems,
             "; ".join(problems) if problems else f"both point to $base/lib/{PACKAGE}",
             f"[develop] script_dir and [install] install_scripts = $base/lib/{PACKAGE}")

    places = ", ".join(relative(s, p / PACKAGE) for p in site_packages(prefix)) or f"{relative(s, prefix)}/lib/python3.*"
    installed_import(s, "python_package", PACKAGE, f"import {PACKAGE} works with the workspace sourced and loads "
                     f"the copy colcon installed under install/ ({places})", note=f" (nothing installed at {places}?)")
