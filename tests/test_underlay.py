"""course/ros/underlay.py on tiny made-up pins: cache, atomic switch, one-line failures, interruption.

The real pins take minutes; these build one small ament_python package with the
same code path (mirror folder, COLCON_IGNORE of unlisted packages, two colcon
passes, stamp, symlink switch) in a few seconds.
"""

from __future__ import annotations

import io
import os
import shutil
import tarfile
import textwrap
from pathlib import Path

import pytest
from ros2course.ros import underlay, underlay_build, underlay_cache
from ros2course.ros.underlay_pins import Pin

#: colcon builds: never beside the determinism tests (conftest.cpu_exclusive)
pytestmark = [pytest.mark.usefixtures("cpu_exclusive"), pytest.mark.timeout(1200)]

COMMIT = "0123456789abcdef0123456789abcdef01234567"


def _add(tar: tarfile.TarFile, name: str, text: str) -> None:
    data = textwrap.dedent(text).encode()
    info = tarfile.TarInfo(name)
    info.size = len(data)
    tar.addfile(info, io.BytesIO(data))


def _package_xml(name: str, build_type: str) -> str:
    return f"""\
        <?xml version="1.0"?>
        <package format="3">
          <name>{name}</name>
          <version>0.0.1</version>
          <description>test package</description>
          <maintainer email="course@example.com">ros2course</maintainer>
          <license>Apache-2.0</license>
          <export><build_type>{build_type}</build_type></export>
        </package>
        """


def make_archive(mirror: Path, repo: str, packages: dict[str, str]) -> Pin:
    """Write ``<mirror>/test--<repo>-<COMMIT>.tar.gz`` holding ``packages`` (name -> "ok"/"broken"/"ignored")."""
    mirror.mkdir(parents=True, exist_ok=True)
    top = f"{repo}-{COMMIT}"
    with tarfile.open(mirror / f"test--{repo}-{COMMIT}.tar.gz", "w:gz") as tar:
        for name, kind in packages.items():
            if kind == "broken":
                _add(tar, f"{top}/{name}/package.xml", _package_xml(name, "cmake"))
                _add(tar, f"{top}/{name}/CMakeLists.txt",
                     f'cmake_minimum_required(VERSION 3.8)\nproject({name})\nmessage(FATAL_ERROR "broken on purpose")\n')
                continue
            _add(tar, f"{top}/{name}/package.xml", _package_xml(name, "ament_python"))
            _add(tar, f"{top}/{name}/resource/{name}", "")
            _add(tar, f"{top}/{name}/{name}/__init__.py", "VALUE = 42\n")
            _add(tar, f"{top}/{name}/setup.py", f"""\
                from setuptools import setup
                setup(name={name!r}, version='0.0.1', packages=[{name!r}],
                      data_files=[('share/ament_index/resource_index/packages', ['resource/{name}']),
                                  ('share/{name}', ['package.xml'])])
                """)
            if kind == "ignored":  # a package that must get a COLCON_IGNORE (it would fail to build)
                _add(tar, f"{top}/{name}/setup.py", "raise SystemExit('must not be built')\n")
    return Pin("test", repo, COMMIT, "0.0.1", tuple(n for n, k in packages.items() if k != "ignored"))


@pytest.fixture
def mirror(tmp_path: Path) -> Path:
    return tmp_path / "mirror"


@pytest.fixture(autouse=True)
def own_build_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Each test its own machine-wide cache (ros2course.ros.underlay_cache): no test restores another's build."""
    monkeypatch.setenv("ROS2COURSE_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache"


@pytest.mark.timeout(1200)
def test_build_caches_switches_atomically_and_keeps_the_old_underlay_on_failure(tmp_path, mirror):
    base = tmp_path / "underlay"
    tiny = make_archive(mirror, "tiny", {"tiny_pkg": "ok", "tiny_fixture": "ignored"})

    made, built = underlay_build.build(mirror, pins=(tiny,), base=base)
    assert built
    assert (base / "current").is_symlink()
    assert made.prefix == (base / "builds" / underlay.cache_key((tiny,))).resolve()
    assert (made.prefix / "share" / "ament_index" / "resource_index" / "packages" / "tiny_pkg").is_file()
    assert not (made.prefix / "share" / "ament_index" / "resource_index" / "packages" / "tiny_fixture").exists()
    assert made.commit_of("tiny") == COMMIT
    assert not (base / "work").exists()

    again, built_again = underlay_build.build(mirror, pins=(tiny,), base=base)
    assert not built_again and again.prefix == made.prefix

    broken = make_archive(mirror, "broken", {"broken_pkg": "broken"})
    with pytest.raises(underlay.UnderlayBuildFailed) as failure:
        underlay_build.build(mirror, pins=(tiny, broken), base=base)
    message = failure.value.message
    assert "\n" not in message and failure.value.hint == ""
    assert "(package broken_pkg)" in message
    log = Path(message.rsplit("log: ", 1)[1])
    assert "broken on purpose" in log.read_text(encoding="utf-8")
    still = underlay.current(base)
    assert still is not None and still.prefix == made.prefix
    assert sorted(p.name for p in (base / "builds").iterdir()) == [made.prefix.name]

    missing = Pin("test", "absent", COMMIT, "0", None)
    with pytest.raises(underlay.UnderlayBuildFailed, match="is not in the sources folder"):
        underlay_build.build(mirror, pins=(tiny, missing), base=base)
    assert underlay.current(base).prefix == made.prefix


@pytest.mark.timeout(1200)
def test_an_interrupted_build_leaves_nothing_a_later_run_trusts(tmp_path, mirror, monkeypatch):
    base = tmp_path / "underlay"
    tiny = make_archive(mirror, "tiny", {"tiny_pkg": "ok"})
    real = underlay_build._run_colcon

    def interrupted(args, env, cwd, log, timeout, packages=None):
        real(args, env, cwd, log, timeout, packages)  # the packages get installed, then Ctrl+C before the stamp
        raise KeyboardInterrupt

    monkeypatch.setattr(underlay_build, "_run_colcon", interrupted)
    with pytest.raises(KeyboardInterrupt):
        underlay_build.build(mirror, pins=(tiny,), base=base)
    assert underlay.current(base) is None
    assert not (base / "current").exists()
    assert not underlay.up_to_date(base, (tiny,))
    assert list((base / "builds").iterdir()) == []

    monkeypatch.setattr(underlay_build, "_run_colcon", real)
    made, built = underlay_build.build(mirror, pins=(tiny,), base=base)
    assert built and underlay.up_to_date(base, (tiny,))


def test_a_damaged_archive_fails_in_one_line(tmp_path, mirror):
    mirror.mkdir()
    pin = Pin("test", "damaged", COMMIT, "0", None)
    (mirror / pin.archive_name).write_bytes(b"not a gzip file")
    with pytest.raises(underlay.UnderlayBuildFailed) as failure:
        underlay_build.build(mirror, pins=(pin,), base=tmp_path / "underlay")
    assert "cannot be unpacked" in failure.value.message and "log: " in failure.value.message
    assert "\n" not in failure.value.message


def test_cache_key_follows_pins_and_repairs(monkeypatch):
    first = Pin("o", "r", COMMIT, "1")
    assert underlay.cache_key((first,)) == underlay.cache_key((Pin("o", "r", COMMIT, "1"),))
    assert underlay.cache_key((first,)) != underlay.cache_key((Pin("o", "r", "f" * 40, "1"),))
    before = underlay.cache_key((first,))
    monkeypatch.setattr(underlay, "REPAIRS_VERSION", underlay.REPAIRS_VERSION + 1)
    assert underlay.cache_key((first,)) != before


def test_github_urls_of_the_pins():
    pin = Pin("ros2", "rclcpp", COMMIT, "28")
    assert pin.url == f"https://github.com/ros2/rclcpp/archive/{COMMIT}.tar.gz"
    assert pin.archive_name == f"ros2--rclcpp-{COMMIT}.tar.gz"
    assert pin.top == f"rclcpp-{COMMIT}"


@pytest.mark.timeout(1200)
def test_a_second_install_restores_the_cached_build_relocated_and_rebuild_ignores_it(tmp_path, mirror, own_build_cache):
    tiny = make_archive(mirror, "tiny", {"tiny_pkg": "ok"})
    first, built = underlay_build.build(mirror, pins=(tiny,), base=tmp_path / "first")
    assert built and "restored_from" not in first.stamp
    entries = list((own_build_cache / "underlay").iterdir())
    assert [e.name for e in entries] == [f"jazzy-{first.stamp['portable']}"]
    assert str(first.prefix) in (first.prefix / "local_setup.sh").read_text(encoding="utf-8")

    # another install (another root): restored, and its setup script names its own prefix, not the first one's
    second, built = underlay_build.build(mirror, pins=(tiny,), base=tmp_path / "second")
    assert built and second.stamp["restored_from"] == str(entries[0])
    setup = (second.prefix / "local_setup.sh").read_text(encoding="utf-8")
    assert str(second.prefix) in setup and str(first.prefix) not in setup
    assert (second.prefix / "share" / "ament_index" / "resource_index" / "packages" / "tiny_pkg").is_file()
    assert underlay.up_to_date(tmp_path / "second", (tiny,))

    # --rebuild builds from source; ROS2COURSE_UNDERLAY_CACHE=0 neither reads nor writes the cache
    again, built = underlay_build.build(mirror, pins=(tiny,), base=tmp_path / "second", force=True)
    assert built and "restored_from" not in again.stamp and "log" in again.stamp
    shutil.rmtree(own_build_cache)
    os.environ["ROS2COURSE_UNDERLAY_CACHE"] = "0"
    try:
        third, built = underlay_build.build(mirror, pins=(tiny,), base=tmp_path / "third")
    finally:
        del os.environ["ROS2COURSE_UNDERLAY_CACHE"]
    assert built and "restored_from" not in third.stamp and not own_build_cache.exists()


def test_restore_relocates_text_files_symlinks_and_scripts_and_leaves_binaries(tmp_path, own_build_cache):
    old_venv, new_venv = "/old/clone/.venv", "/new/checkout/.venv"
    old_prefix, new_prefix = f"{old_venv}/opt/u/builds/aaaa", tmp_path / "new" / "builds" / "bbbb"
    built = tmp_path / "built"
    (built / "bin").mkdir(parents=True)
    (built / "share" / "pkg" / "__pycache__").mkdir(parents=True)
    script = built / "bin" / "ros2"
    script.write_text(f"#!{old_venv}/bin/python3\nimport sys\n")
    script.chmod(0o755)
    (built / "share" / "pkg" / "parent_prefix_path").write_text(f"{old_prefix}:/below/old:{old_venv}/lib")
    (built / "share" / "pkg" / "__pycache__" / "x.pyc").write_bytes(f"{old_prefix}".encode())
    (built / "lib.so").write_bytes(b"\x7fELF\0\0" + old_prefix.encode())
    (built / "share" / "link").symlink_to(f"{old_prefix}/bin/ros2")
    paths = {"prefix": old_prefix, "below": "/below/old", "venv": old_venv}
    entry = underlay_cache.save(built, "jazzy", "0123456789abcdef", paths)
    assert entry is not None and underlay_cache.lookup("jazzy", "0123456789abcdef") == entry

    rewritten = underlay_cache.restore(entry, new_prefix,
                                       {"prefix": str(new_prefix), "below": "/below/new", "venv": new_venv})
    assert rewritten == 3
    assert (new_prefix / "bin" / "ros2").read_text().startswith(f"#!{new_venv}/bin/python3\n")
    assert os.access(new_prefix / "bin" / "ros2", os.X_OK)
    assert (new_prefix / "share" / "pkg" / "parent_prefix_path").read_text() == \
        f"{new_prefix}:/below/new:{new_venv}/lib"
    assert os.readlink(new_prefix / "share" / "link") == f"{new_prefix}/bin/ros2"
    assert (new_prefix / "lib.so").read_bytes() == (built / "lib.so").read_bytes()
    assert not (new_prefix / "share" / "pkg" / "__pycache__").exists()
    assert underlay_cache.lookup("jazzy", "fedcba9876543210") is None


def test_the_portable_key_follows_the_pins_and_the_wheels_never_the_install_path(monkeypatch):
    tiny = Pin("test", "tiny", COMMIT, "0.0.1", ("tiny_pkg",))
    key = underlay_cache.portable_key("jazzy", (tiny,))
    monkeypatch.setenv("ROS2COURSE_UNDERLAY", "/somewhere/else")
    assert underlay_cache.portable_key("jazzy", (tiny,)) == key
    assert underlay_cache.portable_key("jazzy", (Pin("test", "tiny", COMMIT, "0.0.2", ("tiny_pkg",)),)) != key
    assert underlay_cache.portable_key("sas", (tiny,), below=key) != key
    monkeypatch.setattr(underlay_cache, "wheel_versions", lambda: [("ros-jazzy-rclcpp-fake", "9.9.9")])
    assert underlay_cache.portable_key("jazzy", (tiny,)) != key
