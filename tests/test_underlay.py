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

#: colcon builds: never beside each other (conftest.cpu_exclusive)
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


# --- The optional nav2 component (nav2 and Gazebo interfaces; issue 40): no build ------------------------------


def test_the_nav2_component_builds_its_interfaces_on_the_underlay_and_leaves_the_jazzy_key_alone():
    from ros2course.ros.underlay_pins import JAZZY, NAV2

    component = underlay.COMPONENTS["nav2"]
    assert component is underlay.NAV2_COMPONENT and component.pins is NAV2 and component.subdir == "nav2"
    assert [c.name for c in underlay.OPTIONAL] == ["sas", "nav2"]
    assert underlay.component_root(component) == underlay.root() / "nav2"
    built = {pin.repo: pin.packages for pin in NAV2}
    assert built == {"ros_gz": ("ros_gz_interfaces",), "geographic_info": ("geographic_msgs",),
                     "navigation2": ("nav2_common", "nav2_msgs")}
    assert [pin.archive_name for pin in NAV2] == [
        "gazebosim--ros_gz-739cb42a5846cd12a526b97ba051a2d8cdbe034b.tar.gz",
        "ros-geographic-info--geographic_info-2a0ae99219645b8d29772b997ef31f8e17345d52.tar.gz",
        "ros-navigation--navigation2-f4108e5b1c2bce804a1aa0c7be6673a8eb4a1501.tar.gz"]
    assert all(pin.mirror_dir == "" and pin.colcon_pass == 1 and not pin.patches for pin in NAV2)
    # the underlay's own pins (and so its key) do not know nav2: adding it rebuilt nothing
    assert not {pin.repo for pin in NAV2} & {pin.repo for pin in JAZZY}
    assert underlay.cache_key() == underlay.cache_key(JAZZY)
    # nav2's key follows its pins and the underlay below it, like sas's
    assert underlay.cache_key(NAV2, "below-1") != underlay.cache_key(NAV2, "below-2")
    assert underlay.cache_key(NAV2, "below-1") != underlay.cache_key(underlay.SAS_COMPONENT.pins, "below-1")
    assert underlay_cache.portable_key("nav2", NAV2, "p") != underlay_cache.portable_key("sas", NAV2, "p")


def test_the_nav2_archives_are_in_the_projects_mirror():
    mirror = underlay.project_mirror()
    if mirror is None:
        pytest.skip("no ../shared/ros-src beside the project")
    assert underlay.missing_archives(underlay.NAV2_COMPONENT.pins, mirror) == []


def test_missing_archives_names_the_files_a_sources_folder_lacks(tmp_path):
    sas_pin = Pin("o", "sub", COMMIT, "1", mirror_dir="sas")
    patched = Pin("o", "patched", COMMIT, "1", patches=("fix.patch",))
    (tmp_path / "sas").mkdir()
    assert underlay.missing_archives((sas_pin, patched), tmp_path) == [
        f"sas/{sas_pin.archive_name}", patched.archive_name, "fix.patch"]
    (tmp_path / "sas" / sas_pin.archive_name).touch()
    (tmp_path / "fix.patch").touch()
    assert underlay.missing_archives((sas_pin, patched), tmp_path) == [patched.archive_name]


def test_nav2_needs_the_nav_msgs_wheel(tmp_path):
    missing = underlay.nav2_missing_prerequisites(tmp_path)
    assert len(missing) == 1 and "nav_msgs" in missing[0][0] and missing[0][1] == "pip install 'ros2course[nav2]'"
    config = tmp_path / "share" / "nav_msgs" / "cmake" / "nav_msgsConfig.cmake"
    config.parent.mkdir(parents=True)
    config.touch()
    assert underlay.nav2_missing_prerequisites(tmp_path) == []
    assert underlay.component_missing_prerequisites(underlay.JAZZY_COMPONENT) == []


@pytest.fixture
def underlay_built_elsewhere(tmp_path, monkeypatch):
    """underlay_build.build of an optional component as if the underlay were built, without touching the venv."""
    from ros2course.ros.env import RosInstall

    monkeypatch.setattr(underlay_build, "built", lambda component: underlay.Underlay(tmp_path / "jazzy", {"key": "k"}))
    monkeypatch.setattr(underlay_build, "detect", lambda: RosInstall("none", None, None))
    monkeypatch.setattr(underlay_build, "missing_prerequisites", lambda: [])
    return tmp_path / "nav2"


def test_with_nav2_and_a_sources_folder_without_its_archives_fails_in_one_line(tmp_path, underlay_built_elsewhere,
                                                                                monkeypatch):
    monkeypatch.setattr(underlay, "nav2_missing_prerequisites", lambda prefix=None: [])
    empty = tmp_path / "old-ros-src"
    empty.mkdir()
    with pytest.raises(underlay.UnderlayBuildFailed) as failure:
        underlay_build.build(empty, component=underlay.NAV2_COMPONENT, base=underlay_built_elsewhere)
    message, hint = failure.value.message, failure.value.hint
    assert message == (f"cannot build {underlay.NAV2_COMPONENT.what}: gazebosim--ros_gz-739cb42a5846cd12a526b97ba051a2"
                       f"d8cdbe034b.tar.gz (and 2 more) is not in the sources folder {empty}")
    assert "\n" not in message and "SOURCES.md" in hint and "ROS2COURSE_ROS_SOURCES" in hint
    assert underlay.current(underlay_built_elsewhere) is None
    assert not list((underlay_built_elsewhere / "logs").iterdir())  # failed before anything was unpacked


def test_with_nav2_but_without_the_nav_msgs_wheel_says_which_extra(tmp_path, underlay_built_elsewhere, monkeypatch):
    monkeypatch.setattr(underlay, "nav2_missing_prerequisites", lambda prefix=None: [("no nav_msgs", "pip install x")])
    with pytest.raises(underlay.UnderlayBuildFailed) as failure:
        underlay_build.build(tmp_path, component=underlay.NAV2_COMPONENT, base=underlay_built_elsewhere)
    assert failure.value.message == f"cannot build {underlay.NAV2_COMPONENT.what}: no nav_msgs (pip install x)"


def test_env_with_an_unknown_component_names_the_optional_ones():
    from conftest import run_cli_in_process

    result = run_cli_in_process("env", "--build", "--with", "gazebo")
    assert result.returncode == 5
    assert "unknown component 'gazebo'" in result.stderr and "sas, nav2" in result.stderr
    result = run_cli_in_process("env", "--path", "--with", "nav2")
    assert result.returncode == 5 and "goes with --build" in result.stderr


def test_the_doctor_row_of_nav2(monkeypatch):
    from ros2course.ros import doctor
    from ros2course.ros.env import RosInstall

    wheels = RosInstall("wheels", Path("/venv"), "jazzy")
    monkeypatch.setattr(underlay, "built", lambda component: None)
    monkeypatch.setattr(underlay, "nav2_missing_prerequisites", lambda prefix=None: [])
    row = doctor.nav2_row(wheels)
    assert (row.component, row.ok) == ("nav2 interfaces (optional)", False)
    assert row.detail.startswith("not built") and row.hint.startswith("ros2course env --build --with nav2")
    row = doctor.nav2_row(wheels, failure="building it failed: log: /x.log")
    assert row.detail.startswith("building it failed")
    monkeypatch.setattr(underlay, "nav2_missing_prerequisites",
                        lambda prefix=None: [("no nav_msgs", "pip install 'ros2course[nav2]'")])
    row = doctor.nav2_row(wheels)
    assert "cannot build: no nav_msgs" in row.detail and row.hint == "pip install 'ros2course[nav2]'"

    stamp = {"built": "2026-11-28T10:06:00+00:00", "seconds": 88.5}
    monkeypatch.setattr(underlay, "built", lambda component: underlay.Underlay(Path("/u/nav2/builds/k"), stamp)
                        if component is underlay.NAV2_COMPONENT else None)
    row = doctor.nav2_row(wheels)
    assert row.ok and "nav2_msgs, ros_gz_interfaces" in row.detail and "in 88.5 s into /u/nav2/builds/k" in row.detail

    # a sourced system ROS: nothing is built, the row names the apt packages
    system = RosInstall("system", Path("/opt/ros/jazzy"), "jazzy")
    monkeypatch.setattr(doctor.env_mod, "ament_has", lambda name: name == "nav2_msgs")
    row = doctor.nav2_row(system)
    assert not row.ok and "ros_gz_interfaces not installed" in row.detail
    assert row.hint == "sudo apt-get install ros-jazzy-ros-gz-interfaces ros-jazzy-nav2-msgs"
    monkeypatch.setattr(doctor.env_mod, "ament_has", lambda name: True)
    row = doctor.nav2_row(system)
    assert row.ok and "from the system ROS (/opt/ros/jazzy)" in row.detail and row.hint == ""


def test_the_doctor_rows_of_the_optional_components_come_from_one_function(monkeypatch):
    """sas and nav2 rows: one shape (built, or not built with the command or what the build lacks); a system ROS
    has no sas row (nothing of SmartArmStack is in its apt packages here)."""
    from ros2course.ros import doctor
    from ros2course.ros.env import RosInstall

    wheels = RosInstall("wheels", Path("/venv"), "jazzy")
    monkeypatch.setattr(underlay, "built", lambda component: None)
    monkeypatch.setattr(underlay, "sas_missing_prerequisites", lambda: [("no pybind11", "pip install 'ros2course[sas]'")])
    row = doctor.component_row(underlay.SAS_COMPONENT, wheels)
    assert (row.component, row.ok) == ("sas (optional)", False)
    assert "cannot build: no pybind11" in row.detail and "sas lesson" in row.detail
    assert row.hint == "pip install 'ros2course[sas]'"
    stamp = {"built": "2026-11-28T10:00:00+00:00", "restored_from": "/cache/x.tar"}
    monkeypatch.setattr(underlay, "built", lambda component: underlay.Underlay(Path("/u/sas/builds/k"), stamp))
    row = doctor.component_row(underlay.SAS_COMPONENT, wheels)
    assert row.ok and row.detail.startswith(f"{len(underlay.SAS_COMPONENT.pins)} pinned repos, restored")
    assert doctor.component_row(underlay.SAS_COMPONENT, RosInstall("system", Path("/opt/ros/jazzy"), "jazzy")) is None
    assert doctor.NAV2_PROVIDES == {"ros_gz_interfaces", "geographic_msgs", "nav2_common", "nav2_msgs", "nav_msgs"}


def test_activation_puts_a_built_nav2_on_top_of_the_underlay(tmp_path, monkeypatch):
    import sys

    from ros2course.ros import env as env_mod

    jazzy = underlay.Underlay(tmp_path / "jazzy", {"component": "jazzy"})
    nav2 = underlay.Underlay(tmp_path / "nav2", {"component": "nav2"})
    monkeypatch.setattr(underlay, "current", lambda base=None: jazzy)
    monkeypatch.setattr(underlay, "built", lambda component: nav2 if component is underlay.NAV2_COMPONENT else None)
    install = env_mod.RosInstall("wheels", Path(sys.prefix), "jazzy")

    def ament(**kwargs) -> list[str]:
        return [value for op, var, value in env_mod.activation(install, **kwargs) if var == "AMENT_PREFIX_PATH"]

    assert ament() == [sys.prefix, str(jazzy.prefix), str(nav2.prefix)]  # later prepends come first
    assert ament(nav2=False) == [sys.prefix, str(jazzy.prefix)]
    assert ament(underlay=False) == [sys.prefix]
    paths = [value for op, var, value in env_mod.activation(install) if var == "PYTHONPATH"]
    assert paths[-1] == str(nav2.site_packages)


def test_the_wheel_repair_covers_nav_msgs(tmp_path):
    import sysconfig

    from ros2course.ros import env as env_mod

    # the line the ros-jazzy-nav-msgs 5.3.6 wheel ships (as the other message wheels the set-up repairs)
    export = tmp_path / "share" / "nav_msgs" / "cmake" / "export_nav_msgs__rosidl_generator_pyExport.cmake"
    export.parent.mkdir(parents=True)
    export.write_text('  INTERFACE_INCLUDE_DIRECTORIES "/opt/python/cp311-cp311/include/python3.11;'
                      '/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include"\n')
    assert env_mod.cmake_files_needing_repair(tmp_path) == [export]
    assert env_mod.repair_cmake_files(tmp_path) == [export]
    paths = sysconfig.get_paths()
    assert export.read_text() == (f'  INTERFACE_INCLUDE_DIRECTORIES "{paths["include"]};'
                                  f'{paths["purelib"]}/numpy/_core/include"\n')
    assert env_mod.repair_cmake_files(tmp_path) == [] and env_mod.cmake_files_needing_repair(tmp_path) == []
