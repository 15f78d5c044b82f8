"""graders/kit/launch.py: the static reader of Python launch files (feedback, the sas grader's parameters),
the launch_ros command line start_node_action gives a node, and how a learner's launch file is run.

No ROS node is started: a stand-in session records what would be launched.
"""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import pytest
import yaml

from ros2course.lesson.catalog import content_root
from ros2course.kit import launch as _launch
from ros2course.kit.launch import (
    MODE_LAUNCH_ROS,
    read_launch_file,
    start_launch_file,
    start_node_action,
)

REFERENCE = (content_root() / "solutions" / "src" / "python_package_that_uses_parameters_and_launch_files"
             / "launch" / "peanut_butter_falcon_quote_publisher_launch.py")


def write(tmp_path: Path, text: str, name: str = "x_launch.py") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


class FakeSession:
    """The two GradingSession methods start_launch_file uses, recording instead of running."""

    def __init__(self, tmp_path: Path, executables: dict[tuple[str, str], Path] | None = None) -> None:
        self.log_dir = tmp_path / "log"
        self.log_dir.mkdir()
        self.executables = executables or {}
        self.launched: list[tuple[Path, str, list[str]]] = []

    def find_executable(self, package: str, executable: str):
        path = self.executables.get((package, executable))
        return (path, str(path)) if path else (None, f"no executable {executable} in {package}")

    def launch(self, path: Path, name: str, args: list[str] | None = None):
        self.launched.append((path, name, list(args or [])))

        class Proc:
            def poll(self):
                return None
        return Proc()


# --- reading ----------------------------------------------------------------------------

def test_reference_launch_file_is_read_with_its_literal_arguments():
    found = read_launch_file(REFERENCE)
    assert found.problems == []
    assert len(found.nodes) == 1
    node = found.nodes[0]
    assert node.supported, node.unsupported
    assert node.package == "python_package_that_uses_parameters_and_launch_files"
    assert node.executable == "amazing_quote_configurable_publisher_node"
    assert node.name == "peanut_butter_falcon_quote_publisher_node"
    assert node.fully_qualified_name() == "/peanut_butter_falcon_quote_publisher_node"
    (params,) = node.parameters
    assert params["topic_name"] == "truly_inspirational_quote"
    assert params["period"] == 0.25 and isinstance(params["period"], float)
    assert params["philosopher_name"] == "Tyler"
    # adjacent string literals are one literal: glued exactly as Python glues them
    assert params["quote"].startswith("Yeah, you're gonna die, it's a matter of time. That ain't the question. The")
    assert params["quote"].endswith("when you're gone")


def test_module_style_node_namespace_remappings_and_arguments(tmp_path):
    path = write(tmp_path, """
        import launch
        import launch_ros.actions

        def generate_launch_description():
            return launch.LaunchDescription([
                launch_ros.actions.Node(
                    package='pkg', executable='exe', name='n', namespace='robot',
                    parameters=[{'a': 1, 'nested': {'b': [1.0, 2.0]}}, '/tmp/extra.yaml'],
                    remappings=[('chatter', 'talk')], arguments=['--flag'], output='screen', emulate_tty=True),
            ])
        """)
    (node,) = read_launch_file(path).nodes
    assert node.supported, node.unsupported
    assert node.fully_qualified_name() == "/robot/n"
    assert node.parameters == [{"a": 1, "nested.b": [1.0, 2.0]}, "/tmp/extra.yaml"]
    files = node.parameter_files()
    assert files[0] == {"/robot/n": {"ros__parameters": {"a": 1, "nested.b": [1.0, 2.0]}}}
    assert files[1] == "/tmp/extra.yaml"
    assert node.ros_args(["/tmp/p0.yaml", "/tmp/extra.yaml"]) == [
        "--flag", "--ros-args", "-r", "__node:=n", "-r", "__ns:=/robot",
        "--params-file", "/tmp/p0.yaml", "--params-file", "/tmp/extra.yaml", "-r", "chatter:=talk"]


def test_aliased_import_is_recognised(tmp_path):
    path = write(tmp_path, """
        from launch import LaunchDescription
        from launch_ros.actions import Node as RosNode

        def generate_launch_description():
            node = RosNode(package='p', executable='e')
            return LaunchDescription([node])
        """)
    (node,) = read_launch_file(path).nodes
    assert node.supported
    assert node.fully_qualified_name() is None
    assert node.parameter_files() == []
    assert node.ros_args([]) == ["--ros-args"]


def test_a_node_without_a_name_gets_the_wildcard_parameters_key(tmp_path):
    path = write(tmp_path, """
        from launch import LaunchDescription
        from launch_ros.actions import Node

        def generate_launch_description():
            return LaunchDescription([Node(package='p', executable='e', parameters=[{'x': 'y'}])])
        """)
    (node,) = read_launch_file(path).nodes
    assert node.parameter_files() == [{"/**": {"ros__parameters": {"x": "y"}}}]


@pytest.mark.parametrize(("argument", "words"), [
    ("name=NAME", "NAME is not a literal"),
    ("name=f'{NAME}'", "is not a literal"),
    ("parameters=[PARAMS]", "[PARAMS] is not a literal"),
    ("parameters=[{'period': 0.25 * 2}]", "is not a literal"),
    ("parameters=[{'a': object}]", "is not a literal"),
    ("parameters={'a': 1}", "expected a list"),
    ("parameters=[{'a': None}]", "is not a parameter value"),
    ("remappings=[('a',)]", "(from, to) string pairs"),
    ("condition=IfCondition('true')", "not supported"),
    ("**KWARGS", "**KWARGS is not a literal"),
], ids=["variable", "f-string", "list-of-variable", "arithmetic", "name-in-dict", "dict-not-list", "none-value",
        "bad-remap", "unknown-kwarg", "double-star"])
def test_non_literal_or_unsupported_arguments_are_reported_not_guessed(tmp_path, argument, words):
    path = write(tmp_path, f"""
        from launch import LaunchDescription
        from launch_ros.actions import Node
        NAME = 'n'
        PARAMS = {{'a': 1}}
        KWARGS = {{'name': 'n'}}

        def generate_launch_description():
            return LaunchDescription([Node(package='p', executable='e', {argument})])
        """)
    (node,) = read_launch_file(path).nodes
    assert not node.supported
    assert any(words in problem for problem in node.unsupported), node.unsupported


def test_positional_arguments_and_missing_executable_are_reported(tmp_path):
    path = write(tmp_path, """
        from launch import LaunchDescription
        from launch_ros.actions import Node

        def generate_launch_description():
            return LaunchDescription([Node('p', 'e'), Node(package='p')])
        """)
    first, second = read_launch_file(path).nodes
    assert any("positional" in u for u in first.unsupported)
    assert any("no executable=" in u for u in second.unsupported)


@pytest.mark.parametrize(("text", "words"), [
    ("def generate_launch_description(:\n    pass\n", "syntax error"),
    ("from launch_ros.actions import Node\nX = Node(package='p', executable='e')\n",
     "no generate_launch_description"),
    ("from somewhere import Node\ndef generate_launch_description():\n    return [Node(package='p', executable='e')]\n",
     "not imported from launch_ros.actions"),
], ids=["syntax-error", "no-function", "node-not-from-launch-ros"])
def test_files_that_cannot_launch_are_problems(tmp_path, text, words):
    found = read_launch_file(write(tmp_path, text))
    assert found.nodes == []
    assert any(words in p for p in found.problems), found.problems


def test_a_name_never_imported_is_a_problem(tmp_path):
    """``from launch import LaunchDescription`` forgotten: ros2 launch would stop with a NameError
    (a survivor of ``dev mutate sas-robot-driver`` until pyflakes read the file)."""
    found = read_launch_file(write(tmp_path, """
        from launch_ros.actions import Node

        def generate_launch_description():
            return LaunchDescription([Node(package='p', executable='e')])
        """))
    assert [n.executable for n in found.nodes] == ["e"]
    assert found.problems == ["x_launch.py line 5: name 'LaunchDescription' is not defined (not imported: ros2 "
                              "launch would stop with a NameError)"], found.problems
    imported = read_launch_file(write(tmp_path, """
        from launch import LaunchDescription
        from launch_ros.actions import Node

        def generate_launch_description():
            return LaunchDescription([Node(package='p', executable='e')])
        """))
    assert imported.problems == []


def test_reading_executes_nothing(tmp_path):
    """A launch file with side effects at import and in generate_launch_description leaves no trace."""
    marker = tmp_path / "was_executed.txt"
    path = write(tmp_path, f"""
        from pathlib import Path
        Path({str(marker)!r}).write_text('module level')
        from launch import LaunchDescription
        from launch_ros.actions import Node

        def generate_launch_description():
            Path({str(marker)!r}).write_text('inside generate_launch_description')
            return LaunchDescription([Node(package='p', executable='e', name=open({str(marker)!r}, 'w').name)])
        """)
    # a first reading loads the reader's own lazy imports (pyflakes, on its first use in the process; whether an
    # earlier test used it depends on the order pytest-xdist gave): what the second adds would be the file's
    read_launch_file(path)
    modules_before = set(sys.modules)
    found = read_launch_file(path)
    assert not marker.exists()
    assert set(sys.modules) == modules_before, "reading imported something"
    (node,) = found.nodes
    assert not node.supported  # open(...) is a call, not a literal
    assert any("open(" in u for u in node.unsupported)
    assert any("Path(...)" in c for c in found.other_calls)


# --- starting -----------------------------------------------------------------------------

def test_node_action_starts_with_the_params_file_launch_ros_would_write(tmp_path):
    exe = tmp_path / "amazing_quote_configurable_publisher_node"
    session = FakeSession(tmp_path, {("python_package_that_uses_parameters_and_launch_files",
                                      "amazing_quote_configurable_publisher_node"): exe})
    (action,) = read_launch_file(REFERENCE).nodes
    proc, reason = start_node_action(session, action, "x")
    assert proc is not None and reason == ""
    ((path, _name, args),) = session.launched
    assert path == exe
    assert args[:3] == ["--ros-args", "-r", "__node:=peanut_butter_falcon_quote_publisher_node"]
    assert args[3] == "--params-file"
    content = yaml.safe_load(Path(args[4]).read_text(encoding="utf-8"))
    assert content == {"/peanut_butter_falcon_quote_publisher_node": {"ros__parameters": {
        "topic_name": "truly_inspirational_quote", "period": 0.25, "philosopher_name": "Tyler",
        "quote": ("Yeah, you're gonna die, it's a matter of time. That ain't the question. The question's, "
                  "whether they're gonna have a good story to tell about you when you're gone")}}}


def test_node_action_reports_a_missing_executable(tmp_path):
    path = write(tmp_path, """
        from launch import LaunchDescription
        from launch_ros.actions import Node

        def generate_launch_description():
            return LaunchDescription([Node(package='p', executable='missing')])
        """)
    session = FakeSession(tmp_path)
    (action,) = read_launch_file(path).nodes
    proc, reason = start_node_action(session, action, "x")
    assert proc is None and "no executable missing" in reason
    assert session.launched == []


def test_without_launch_ros_a_launch_file_is_not_gradable_and_nothing_starts(tmp_path, monkeypatch):
    from ros2course.errors import MissingRequirement

    monkeypatch.setattr(_launch, "launch_ros_available", lambda: False)
    monkeypatch.setattr("ros2course.ros.env.probe_requirement", lambda name: (False, "launch/launch_ros not importable"))
    session = FakeSession(tmp_path)
    with pytest.raises(MissingRequirement, match="needs launch"):
        start_launch_file(session, REFERENCE)
    assert session.launched == []


def test_with_launch_ros_the_file_is_run_as_ros2_launch_runs_it(tmp_path, monkeypatch):
    monkeypatch.setattr(_launch, "launch_ros_available", lambda: True)
    session = FakeSession(tmp_path)
    run = start_launch_file(session, REFERENCE)
    assert run.mode == MODE_LAUNCH_ROS
    assert run.summary() == MODE_LAUNCH_ROS
    ((path, _name, args),) = session.launched
    assert path == Path(sys.executable)
    assert args[0] == "-c" and "LaunchService" in args[1] and "AnyLaunchDescriptionSource" in args[1]
    assert args[2] == str(REFERENCE)
    compile(args[1], "<launch script>", "exec")
    # the static reading is kept for feedback only
    assert "Node(package='python_package_that_uses_parameters_and_launch_files'" in run.file_contents()


REFUSED_OUTPUTS = ["output=''", "output='screenn'", "output=3", "output={'out': 'screen'}",
                   "output={'stdout': 'sceen'}", "output={'both': ['log', 'terminal']}"]
ACCEPTED_OUTPUTS = ["output='screen'", "output='full'", "output='own_log'", "output={'both': ['log', 'screen']}",
                    "output={'stderr': 'own_log'}", "output=OUTPUT"]


@pytest.mark.parametrize(("argument", "refused"), [*((a, True) for a in REFUSED_OUTPUTS),
                                                   *((a, False) for a in ACCEPTED_OUTPUTS),
                                                   ("name=''", True), ("name='quote-node'", True),
                                                   ("name='2nd'", True), ("name='quote_node'", False)])
def test_an_argument_launch_refuses_ends_the_whole_launch(tmp_path, argument, refused):
    """launch raises ValueError for an output it does not know, launch_ros InvalidNodeNameException for a name
    rcl refuses: the whole launch ends, so the reader lists it among the file's problems (issue 40: a held-out
    mutant of gazebo-custom-nodes, output='', passed launch_files)."""
    found = read_launch_file(write(tmp_path, f"""
        from launch import LaunchDescription
        from launch_ros.actions import Node
        OUTPUT = 'screen'

        def generate_launch_description():
            return LaunchDescription([Node(package='p', executable='e', {argument})])
        """))
    (node,) = found.nodes
    assert bool(node.refused) == refused, node.refused
    assert bool(found.problems) == refused, found.problems
    if refused:
        assert found.problems[0].startswith("line 7: Node(...) ") and "the whole launch ends" in found.problems[0]


@pytest.mark.parametrize("argument", REFUSED_OUTPUTS + ACCEPTED_OUTPUTS[:-1])
def test_the_outputs_refused_are_those_launch_refuses(argument):
    """The reader's rule against launch's own (launch.logging.get_output_loggers, which ExecuteLocal calls)."""
    logging = pytest.importorskip("launch.logging", reason="ROS 2's launch is not importable here")
    if not hasattr(logging, "get_output_loggers"):
        pytest.skip("the launch importable here is not ROS 2's")
    config = eval(argument.removeprefix("output="))  # noqa: S307 - the literals above
    try:
        logging.get_output_loggers("p", config)
        launch_refuses = False
    except (ValueError, TypeError):
        launch_refuses = True
    assert launch_refuses == (argument in REFUSED_OUTPUTS)
