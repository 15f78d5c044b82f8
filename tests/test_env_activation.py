"""course/ros/env.py: the learner's activation script, the wheel link repairs, foreign shebangs. No ROS node runs."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from ros2course.ros import env as env_mod

WHEELS = env_mod.detect().kind == "wheels"
needs_wheels = pytest.mark.skipif(not WHEELS, reason="ROS 2 comes from a sourced system install, not the wheels")


@needs_wheels
def test_setup_script_works_under_set_u_is_idempotent_and_matches_activate(tmp_path):
    script = env_mod.write_setup_script()
    assert script.is_file()
    plain = {"HOME": str(tmp_path), "PATH": "/usr/bin:/bin"}
    proc = subprocess.run(
        ["bash", "-c", f'set -eu; source "{script}"; first="$PATH"; source "{script}"; '
                       f'[ "$first" = "$PATH" ]; env -0'],
        env=plain, capture_output=True, timeout=60, check=False)
    assert proc.returncode == 0, proc.stderr.decode()
    sourced = dict(item.split("=", 1) for item in proc.stdout.decode().split("\0") if "=" in item)
    expected = env_mod.activate(plain)
    for var in ("ROS_DISTRO", "AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH", "LD_LIBRARY_PATH", "PATH",
                env_mod.ENV_MARKER):
        assert sourced.get(var) == expected.get(var), var
    assert sourced["ROS_DISTRO"] == "jazzy"
    assert str(Path(sys.prefix) / "lib") in sourced["LD_LIBRARY_PATH"].split(":")
    assert any(p.endswith(".libs") for p in sourced["LD_LIBRARY_PATH"].split(":"))


@needs_wheels
def test_our_own_ros_distro_is_not_mistaken_for_a_system_install(monkeypatch):
    activated = env_mod.activate()
    for var in ("ROS_DISTRO", "AMENT_PREFIX_PATH", env_mod.ENV_MARKER):
        monkeypatch.setenv(var, activated[var])
    assert env_mod.detect().kind == "wheels"


def test_wheel_link_repairs_drop_the_build_machines_libraries_once(tmp_path):
    fastrtps = tmp_path / "share" / "fastrtps" / "cmake" / "fastrtps-shared-targets.cmake"
    extras = tmp_path / "share" / "tracetools" / "cmake" / "ament_cmake_export_libraries-extras.cmake"
    export = tmp_path / "share" / "tracetools" / "cmake" / "tracetools_exportExport.cmake"
    for path in (fastrtps, extras, export):
        path.parent.mkdir(parents=True, exist_ok=True)
    fastrtps.write_text('INTERFACE_LINK_LIBRARIES "fastcdr;foonathan_memory;-lpthread;dl;/usr/lib64/libtinyxml2.so;rt"\n')
    extras.write_text('set(_exported_library_names "lttng-ust;dl")\n')
    export.write_text('  INTERFACE_LINK_LIBRARIES "lttng-ust;dl;-rdynamic;-ldl"\n')
    assert sorted(env_mod.cmake_files_needing_repair(tmp_path)) == sorted([fastrtps, extras, export])
    assert sorted(env_mod.repair_cmake_files(tmp_path)) == sorted([fastrtps, extras, export])
    assert "tinyxml2" not in fastrtps.read_text() and "foonathan_memory;-lpthread;dl;rt" in fastrtps.read_text()
    assert extras.read_text() == 'set(_exported_library_names "dl")\n'
    assert export.read_text() == '  INTERFACE_LINK_LIBRARIES "dl;-rdynamic;-ldl"\n'
    assert env_mod.repair_cmake_files(tmp_path) == []


@needs_wheels
@pytest.mark.parametrize(("first_line", "foreign"), [
    ("#!/usr/bin/python3", True),
    ("#!/usr/bin/python3.11 -u", True),
    ("#!/usr/bin/env python3", False),
    (f"#!{sys.executable}", False),
    ("#!/bin/bash", False),
    ("\x7fELF", False),
])
def test_a_script_for_another_python_runs_with_ours(tmp_path, first_line, foreign):
    script = tmp_path / "joint_interface_example.py"
    script.write_text(first_line + "\nprint('hi')\n")
    assert env_mod.foreign_python_prefix(script) == ([sys.executable] if foreign else [])


def test_env_path_without_a_flag_is_a_one_line_error(tmp_path):
    proc = subprocess.run([str(Path(sys.executable).parent / "ros2course"), "env"], capture_output=True, text=True,
                          timeout=60, check=False)
    assert proc.returncode == 5
    assert proc.stderr.splitlines()[0] == "error: say what to do: --path or --build"


def _workspace_depending_on(tmp_path: Path, dep: str) -> Path:
    pkg = tmp_path / "ws" / "src" / "sas_robot_driver_myrobot"
    pkg.mkdir(parents=True)
    (pkg / "package.xml").write_text(f"""<?xml version="1.0"?>
<package format="3">
  <name>sas_robot_driver_myrobot</name><version>0.0.1</version><description>d</description>
  <maintainer email="course@example.com">m</maintainer><license>Apache-2.0</license>
  <buildtool_depend>ament_cmake</buildtool_depend><depend>{dep}</depend>
  <export><build_type>ament_cmake</build_type></export>
</package>
""")
    return tmp_path / "ws"


@needs_wheels
def test_a_package_on_sas_builds_the_sas_component_on_demand_or_says_why_not(tmp_path, monkeypatch):
    from ros2course.errors import MissingRequirement
    from ros2course.ros import doctor, underlay, underlay_build

    calls = []
    monkeypatch.setattr(underlay_build, "build", lambda **kw: calls.append(kw["component"].name))
    monkeypatch.setattr(underlay, "missing_prerequisites", lambda: [])
    monkeypatch.setattr(underlay, "sas_missing_prerequisites", lambda: [])
    monkeypatch.setattr(env_mod, "ament_has", lambda name: False)
    ws = _workspace_depending_on(tmp_path, "sas_core")
    assert doctor.ensure_components_for(ws, ["sas_robot_driver_myrobot"]) == ["sas"]
    assert calls == ["sas"]
    assert doctor.ensure_components_for(_workspace_depending_on(tmp_path / "py", "rclpy"),
                                         ["sas_robot_driver_myrobot"]) == []
    monkeypatch.setattr(underlay, "sas_missing_prerequisites",
                        lambda: [("no Eigen 3 headers (/usr/include/eigen3)", "apt-get install libeigen3-dev")])
    with pytest.raises(MissingRequirement, match="depends on sas_core .* no Eigen 3 headers"):
        doctor.ensure_components_for(ws, ["sas_robot_driver_myrobot"])
    assert calls == ["sas"]


@needs_wheels
def test_a_package_on_nav2_msgs_builds_the_nav2_component_on_demand_or_says_why_not(tmp_path, monkeypatch):
    """The nav2 lesson's package (issue 40) depends on nav2_msgs: the component is built as sas is, or the
    check says in one line what is missing (the nav_msgs wheel: the nav2 extra)."""
    from ros2course.errors import MissingRequirement
    from ros2course.ros import doctor, underlay, underlay_build

    calls = []
    monkeypatch.setattr(underlay_build, "build", lambda **kw: calls.append(kw["component"].name))
    monkeypatch.setattr(underlay, "missing_prerequisites", lambda: [])
    monkeypatch.setattr(underlay, "nav2_missing_prerequisites", lambda prefix=None: [])
    monkeypatch.setattr(env_mod, "ament_has", lambda name: False)
    ws = _workspace_depending_on(tmp_path, "nav2_msgs")
    assert doctor.ensure_components_for(ws, ["sas_robot_driver_myrobot"]) == ["nav2"]
    assert calls == ["nav2"]
    monkeypatch.setattr(underlay, "nav2_missing_prerequisites", lambda prefix=None: [
        ("no nav_msgs (the ros-jazzy-nav-msgs wheel; nav2_msgs needs it)", "pip install 'ros2course[nav2]'")])
    with pytest.raises(MissingRequirement, match="depends on nav2_msgs .* no nav_msgs") as raised:
        doctor.ensure_components_for(ws, ["sas_robot_driver_myrobot"])
    assert raised.value.hint == "pip install 'ros2course[nav2]'" and calls == ["nav2"]
