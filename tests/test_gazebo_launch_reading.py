"""gazebo-custom-nodes' launch_files check reads where the thrust launch file points the bridge's config_file from
the file's syntax tree (graders/_gazebo.py), never running it: every usual way of spelling the installed
config_bridge/control_shape_thrust.yaml is read as it, and a path without the folder is not."""

from __future__ import annotations

import pytest

from ros2course.grade.engine import load_grader

SHARE = "get_package_share_directory('python_package_that_uses_gazebo')"


@pytest.fixture(scope="module")
def steps():
    return load_grader("gazebo_custom_nodes").steps


@pytest.mark.parametrize("source", [
    f"config = os.path.join({SHARE}, 'config_bridge', 'control_shape_thrust.yaml')",
    f"config = os.path.join({SHARE}, 'config_bridge/control_shape_thrust.yaml')",
    "config = PathJoinSubstitution([FindPackageShare('python_package_that_uses_gazebo'), 'config_bridge', "
    "'control_shape_thrust.yaml'])",
    f"config = Path({SHARE}) / 'config_bridge' / 'control_shape_thrust.yaml'",
    f"config = {SHARE} + '/config_bridge/' + 'control_shape_thrust.yaml'",
    f"config = f\"{{{SHARE}}}/config_bridge/control_shape_thrust.yaml\"",
    f"FILE = 'control_shape_thrust.yaml'\nfolder = os.path.join({SHARE}, 'config_bridge')\n"
    "config = os.path.join(folder, FILE)",
], ids=["join-parts", "join-one-literal", "substitution", "pathlib", "plus", "f-string", "names"])
def test_the_installed_bridge_file_is_read_however_it_is_spelled(steps, source: str) -> None:
    assert steps._names_installed_bridge_file(source + "\nNode(parameters=[{'config_file': config}])\n")


@pytest.mark.parametrize("source", [
    f"config = os.path.join({SHARE}, 'control_shape_thrust.yaml')",
    f"config = Path({SHARE}) / 'control_shape_thrust.yaml'",
    "config = 'control_shape_thrust.yaml'",
    "config = os.path.join(",
], ids=["join-without-folder", "pathlib-without-folder", "bare-name", "does-not-parse"])
def test_a_path_without_the_config_bridge_folder_is_not(steps, source: str) -> None:
    assert not steps._names_installed_bridge_file(source)
