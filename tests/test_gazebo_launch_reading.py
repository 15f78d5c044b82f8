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
    tree = steps._parse(source + "\nNode(parameters=[{'config_file': config}])\n")
    assert steps._sets_config_file(tree) and steps._names_installed_bridge_file(tree)


@pytest.mark.parametrize("source", [
    "config = os.path.join(get_package_share_directory('another_package'), 'config_bridge', "
    "'control_shape_thrust.yaml')",
    "PACKAGE = None\nconfig = os.path.join(get_package_share_directory(PACKAGE), 'config_bridge', "
    "'control_shape_thrust.yaml')",
    f"config = os.path.join({SHARE}, 'control_shape_thrust.yaml')",
    f"config = Path({SHARE}) / 'control_shape_thrust.yaml'",
    "config = 'control_shape_thrust.yaml'",
    "config = os.path.join(",
], ids=["another-package", "package-none", "join-without-folder", "pathlib-without-folder", "bare-name", "does-not-parse"])
def test_a_path_without_the_config_bridge_folder_is_not(steps, source: str) -> None:
    tree = steps._parse(source)
    assert tree is None or not steps._names_installed_bridge_file(tree)


WRENCH = "/world/shapes_with_tf2_and_wrench/wrench@ros_gz_interfaces/msg/EntityWrench]gz.msgs.EntityWrench"
SET_POSE = "/world/shapes_with_tf2_and_wrench/set_pose@ros_gz_interfaces/srv/SetEntityPose"


def test_a_bridge_argument_is_the_whole_bridge_it_names(steps) -> None:
    """parameter_bridge reads each argument as one bridge: the topic and types exactly, a service's Gazebo types
    optional; a string that only holds the words (wrapped, or the direction flipped) names another bridge."""
    assert steps._bridges(WRENCH, WRENCH) and steps._bridges(f" {WRENCH} ", WRENCH)
    assert steps._bridges(SET_POSE, SET_POSE)
    assert steps._bridges(SET_POSE + "@gz.msgs.Pose@gz.msgs.Boolean", SET_POSE)
    assert not steps._bridges(f"XX{WRENCH}XX", WRENCH)
    assert not steps._bridges(WRENCH.replace("]", "["), WRENCH)
    assert not steps._bridges(WRENCH + "@gz.msgs.Pose", WRENCH)
    assert not steps._bridges(SET_POSE + "XX", SET_POSE)
    assert not steps._bridges(None, WRENCH)


def test_a_node_package_is_read_through_the_name_it_is_given(steps) -> None:
    """``package=PACKAGE`` is read as the constant PACKAGE holds (the static reader reads literals only); a value
    the tree does not show (a call, an argument) is unknown, never wrong."""
    tree = steps._parse("PACKAGE = 'p'\nOTHER = None\nNode(package=PACKAGE)\nNode(package=OTHER)\n"
                        "Node(package=pick())\nNode(executable='x')\n")
    assert steps._node_package(tree, 3) == "p" and steps._node_package(tree, 4) is None
    assert steps._node_package(tree, 5) is steps._UNKNOWN and steps._node_package(tree, 6) is steps._UNKNOWN
