"""Package discovery (ros2course.ros.manifests): what catkin_pkg reads, kept by content (issue 36)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from catkin_pkg.packages import find_packages as catkin_find

from ros2course.errors import NotGradable
from ros2course.lesson import content_root
from ros2course.ros import manifests as packages_mod
from ros2course.ros.manifests import Manifest, find_packages

MANIFEST = ('<?xml version="1.0"?>\n<package format="3">\n  <name>{name}</name>\n  <version>0.0.0</version>\n'
            '  <description>d</description>\n  <maintainer email="a@example.com">a</maintainer>\n'
            '  <license>MIT</license>\n  <depend>rclpy</depend>\n  <test_depend>pytest</test_depend>\n'
            '  <export><build_type>ament_python</build_type></export>\n</package>\n')


@pytest.fixture(autouse=True)
def own_cache(tmp_path, monkeypatch):
    """Every test keeps manifests in a cache folder of its own."""
    monkeypatch.setenv("ROS2COURSE_CACHE_DIR", str(tmp_path / "cache"))


def _package(src: Path, folder: str, name: str) -> Path:
    path = src / folder / "package.xml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(MANIFEST.format(name=name), encoding="utf-8")
    return path


def test_the_course_packages_are_found_as_catkin_pkg_finds_them():
    """Every package of the course's reference, and every attribute the engine and graders read, as
    catkin_pkg's own find_packages gives it (cold, then from the cache)."""
    src = content_root() / "solutions" / "src"
    theirs = {pkg.name: (src / rel, pkg) for rel, pkg in catkin_find(str(src)).items()}
    for _ in range(2):
        ours = find_packages(src)
        assert sorted(ours) == sorted(theirs)
        for name, (folder, manifest) in ours.items():
            folder_c, pkg = theirs[name]
            assert folder == folder_c
            assert manifest.get_build_type() == pkg.get_build_type()
            for key in ("build_depends", "buildtool_depends", "exec_depends", "build_export_depends",
                        "test_depends", "member_of_groups"):
                assert [d.name for d in getattr(manifest, key)] == [d.name for d in getattr(pkg, key)], (name, key)
            assert (manifest.version, manifest.package_format) == (pkg.version, int(pkg.package_format))


def test_a_kept_manifest_spares_the_parser_import(tmp_path):
    """A warm read imports neither catkin_pkg's parser nor pyparsing (about 35 ms of every check)."""
    src = tmp_path / "src"
    _package(src, "a", "pkg_a")
    find_packages(src)  # keeps it
    code = ("import sys; from pathlib import Path; from ros2course.ros.manifests import find_packages; "
            f"found = find_packages(Path({str(src)!r})); "
            "print(sorted(found), 'pyparsing' in sys.modules, 'catkin_pkg.package' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={**os.environ, "ROS2COURSE_CACHE_DIR": os.environ["ROS2COURSE_CACHE_DIR"]})
    assert out.stdout.split() == ["['pkg_a']", "False", "False"], out.stdout + out.stderr


def test_a_manifest_is_read_again_when_its_bytes_change_whatever_its_time(tmp_path):
    """The key is the file's bytes: same size, same modification time, another name is seen."""
    src = tmp_path / "src"
    path = _package(src, "a", "pkg_a")
    stat = path.stat()
    assert list(find_packages(src)) == ["pkg_a"]
    path.write_text(MANIFEST.format(name="pkg_b"), encoding="utf-8")
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert list(find_packages(src)) == ["pkg_b"]


def test_a_cache_entry_another_user_could_write_is_not_trusted(tmp_path):
    """A kept manifest that is group- or world-writable is ignored (parsed again), as the catalog's cache."""
    src = tmp_path / "src"
    path = _package(src, "a", "pkg_a")
    find_packages(src)
    kept = list((tmp_path / "cache" / "manifests").glob("*.json"))
    assert len(kept) == 1
    kept[0].write_text(json.dumps(Manifest(name="forged", version="9").to_json()))
    kept[0].chmod(0o666)
    assert list(find_packages(src)) == ["pkg_a"]
    assert path.is_file()


def test_ignore_markers_hidden_folders_and_nested_packages_follow_catkin_pkg(tmp_path):
    """COLCON_IGNORE / AMENT_IGNORE / CATKIN_IGNORE hide a folder, hidden folders and folders inside a
    package are not searched: the same set catkin_pkg finds."""
    src = tmp_path / "src"
    _package(src, "shown", "shown")
    _package(src, "ignored", "ignored")
    (src / "ignored" / "COLCON_IGNORE").touch()
    _package(src, "deep/AMENT_IGNORE_parent/p", "deep_hidden")
    (src / "deep" / "AMENT_IGNORE_parent" / "AMENT_IGNORE").touch()
    _package(src, ".hidden", "hidden")
    _package(src, "shown/inner", "inner")
    _package(src, "group/nested", "nested")
    theirs = sorted(pkg.name for pkg in catkin_find(str(src)).values())
    assert sorted(find_packages(src)) == theirs == ["nested", "shown"]


def test_two_packages_of_one_name_are_not_gradable(tmp_path):
    """colcon refuses a workspace with two packages of one name: a one-line error naming both."""
    src = tmp_path / "src"
    _package(src, "one", "twin")
    _package(src, "two", "twin")
    with pytest.raises(NotGradable, match="two packages are named twin"):
        find_packages(src)


def test_the_kept_manifests_are_capped(tmp_path, monkeypatch):
    """The cache folder keeps at most its limit of manifests (a class graded on one machine adds many)."""
    monkeypatch.setattr(packages_mod, "_CACHE_LIMIT", 3)
    src = tmp_path / "src"
    for i in range(6):
        _package(src, f"p{i}", f"pkg_{i}")
    assert len(find_packages(src)) == 6
    assert len(list((tmp_path / "cache" / "manifests").glob("*.json"))) == 3
