"""The real ROS 2 tools on the default install: the ``ros2`` CLI, ``ros2 launch``, rclcpp, a learner's terminal.

On the PyPI install they come from the source-built underlay (course/ros/underlay.py,
``ros2course env --build``); with a sourced system ROS 2 from there. Every test
holds its own ``ROS_DOMAIN_ID`` (``ros2course.run.probes.RosSession``), discovery on
localhost, and passes ``--no-daemon`` where the verb has it; a ``ros2`` daemon
started in that domain anyway is stopped by PID at the end.
"""

from __future__ import annotations

import os
import shlex
import shutil
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import psutil
import pytest

from ros2course.lesson.catalog import content_root
from ros2course.ros import env as env_mod

ROOT = content_root()
ROS2 = shutil.which("ros2", path=os.environ.get("PATH"))
ROS2COURSE = Path(sys.executable).parent / "ros2course"

pytestmark = [
    pytest.mark.ros,
    # they compile C++: never beside each other (conftest.cpu_exclusive), which may wait for them
    pytest.mark.usefixtures("cpu_exclusive"),
    pytest.mark.timeout(1200),
    pytest.mark.skipif(ROS2 is None, reason="no ros2 command: the ROS 2 underlay is not built "
                       "(ros2course env --build) and no system ROS 2 is sourced"),
]


@pytest.fixture
def session():
    """A private ROS domain with the grader's probes; afterwards, any ros2 daemon of that domain is stopped."""
    from ros2course.run.probes import RosSession  # noqa: PLC0415

    with RosSession() as ros:
        yield ros
        domain = str(ros.domain_id)
        for proc in psutil.process_iter(["cmdline"]):
            try:
                if any("_ros2_daemon" in part for part in proc.info["cmdline"] or []) \
                        and proc.environ().get("ROS_DOMAIN_ID") == domain:
                    os.kill(proc.pid, signal.SIGTERM)
                    proc.wait(5)
            except (psutil.Error, OSError):
                continue


@pytest.fixture
def ros_env(session) -> dict[str, str]:
    env = env_mod.activate()
    return session.learner_env(env)


def ros2(*args: str, env: dict[str, str], timeout: float = 60, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([ROS2, *args], env=env, capture_output=True, text=True, timeout=timeout, cwd=cwd,
                          stdin=subprocess.DEVNULL, start_new_session=True, check=False)


TALKER = """
import rclpy
from rclpy.executors import ExternalShutdownException
from std_msgs.msg import String

rclpy.init()
node = rclpy.create_node("cli_test_talker")
node.declare_parameter("quote", "Use the force, Pikachu!")
pub = node.create_publisher(String, "cli_test_chatter", 10)
count = [0]

def tick():
    pub.publish(String(data=f"hello {count[0]}"))
    count[0] += 1

node.create_timer(0.1, tick)
try:
    rclpy.spin(node)
except (KeyboardInterrupt, ExternalShutdownException):
    pass
"""


@pytest.fixture
def talker(session, ros_env, tmp_path):
    """A Python node publishing std_msgs/String on /cli_test_chatter with a parameter ``quote``."""
    from ros2course.run.process import LearnerProcess  # noqa: PLC0415

    script = tmp_path / "talker.py"
    script.write_text(TALKER, encoding="utf-8")
    proc = LearnerProcess([sys.executable, str(script)], ros_env, tmp_path / "logs", "talker", ros_sigint=True).start()
    try:
        assert session.wait_for_node("cli_test_talker", 20.0, abort=lambda: proc.poll() is not None), proc.stderr()
        yield proc
    finally:
        proc.stop()


def test_ros2_help_lists_the_tutorials_verbs():
    proc = subprocess.run([ROS2, "--help"], capture_output=True, text=True, timeout=60, check=False)
    assert proc.returncode == 0, proc.stderr
    for verb in ("run", "topic", "service", "param", "node", "interface", "launch", "pkg"):
        assert f"\n  {verb} " in proc.stdout, f"ros2 {verb} missing from:\n{proc.stdout}"


def test_topic_echo_once_and_param_get_on_a_running_node(talker, ros_env):
    echo = ros2("topic", "echo", "--once", "--no-daemon", "/cli_test_chatter", "std_msgs/msg/String", env=ros_env)
    assert echo.returncode == 0, echo.stderr
    assert "data: hello " in echo.stdout
    get = ros2("param", "get", "--no-daemon", "--spin-time", "3", "--timeout", "10", "/cli_test_talker", "quote",
               env=ros_env)
    assert get.returncode == 0, get.stderr
    assert get.stdout.strip() == "String value is: Use the force, Pikachu!"


def test_interface_show(ros_env):
    proc = ros2("interface", "show", "geometry_msgs/msg/Point", env=ros_env)
    assert proc.returncode == 0, proc.stderr
    assert [line.split("#")[0].split() for line in proc.stdout.splitlines() if line.strip()
            and not line.startswith("#")] == [["float64", "x"], ["float64", "y"], ["float64", "z"]]


def _activated_bash(script: str, cwd: Path, timeout: float, env: dict[str, str] | None = None
                    ) -> subprocess.CompletedProcess:
    """``bash -lc`` with a plain environment and only the activation line before ``script``."""
    plain = {"HOME": os.environ.get("HOME", "/root"), "PATH": "/usr/local/bin:/usr/bin:/bin",
             "LANG": os.environ.get("LANG", "C.UTF-8"), **(env or {})}
    # the activation script must work under set -u; colcon's install/setup.bash does not (ROS_ENV.md)
    line = f'set -u; source "$({shlex.quote(str(ROS2COURSE))} env --path)"; set +u; set -e; {script}'
    return subprocess.run(["bash", "-lc", line], cwd=cwd, env=plain, capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL, start_new_session=True, check=False)


@pytest.fixture(scope="module")
def built_solutions(tmp_path_factory) -> Path:
    """The reference solutions/ workspace, copied and built with colcon in a learner's terminal."""
    ws = tmp_path_factory.mktemp("solutions_ws")
    shutil.copytree(ROOT / "solutions" / "src", ws / "src",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "build", "install", "log"))
    proc = _activated_bash("colcon build", ws, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return ws


@pytest.mark.timeout(900)
def test_learners_terminal_builds_the_whole_reference_workspace(built_solutions):
    packages = sorted(p.name for p in (ROOT / "solutions" / "src").iterdir() if (p / "package.xml").is_file())
    for name in packages:
        assert (built_solutions / "install" / name).is_dir(), f"{name} not installed"
    probe = _activated_bash(
        'echo "distro=$ROS_DISTRO"; command -v ros2 colcon; source install/setup.bash; '
        'ros2 pkg prefix package_with_interfaces; '
        'python3 -c "from package_with_interfaces.msg import AmazingQuote; print(AmazingQuote().quote == \'\')"',
        built_solutions, timeout=120)
    assert probe.returncode == 0, probe.stderr
    lines = probe.stdout.splitlines()
    assert lines[0] == "distro=jazzy"
    assert lines[1].endswith("/ros2") and lines[2].endswith("/colcon")
    assert lines[3] == str(built_solutions / "install" / "package_with_interfaces")
    assert lines[4] == "True"


@pytest.mark.timeout(600)
def test_ros2_pkg_create_both_build_types_then_plain_colcon_build(tmp_path):
    """The tutorial's ros2 pkg create, then colcon build as typed (BUILD_TESTING on: ament_lint_auto needed)."""
    (tmp_path / "src").mkdir()
    proc = _activated_bash(
        "cd src; ros2 pkg create --build-type ament_cmake --dependencies rclcpp --node-name cpp_node cpp_pkg; "
        "ros2 pkg create --build-type ament_python --dependencies rclpy --node-name py_node py_pkg; cd ..; "
        "colcon build; source install/setup.bash; ros2 run cpp_pkg cpp_node; ros2 run py_pkg py_node",
        tmp_path, timeout=540)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "hello world cpp_pkg package" in proc.stdout
    assert "Hi from py_pkg." in proc.stdout


@pytest.mark.timeout(300)
def test_ros2_launch_of_the_courses_launch_file(built_solutions, session, ros_env, tmp_path):
    from ros2course.run.process import LearnerProcess  # noqa: PLC0415

    launch = LearnerProcess(
        ["bash", "-c", "source install/setup.bash && exec ros2 launch "
         "python_package_that_uses_parameters_and_launch_files peanut_butter_falcon_quote_publisher_launch.py"],
        # launch_ros writes the node's parameters to a launch_params_* file in TMPDIR and never removes it
        # (the engine gives learner processes the check's own TMPDIR: grade/machine.py); here, the test's folder
        {**ros_env, "TMPDIR": str(tmp_path)}, tmp_path / "logs", "ros2_launch", cwd=built_solutions).start()
    try:
        assert session.wait_for_node("peanut_butter_falcon_quote_publisher_node", 30.0,
                                     abort=lambda: launch.poll() is not None), launch.stderr()
        echo = subprocess.run(
            ["bash", "-c", "source install/setup.bash && ros2 topic echo --once --no-daemon "
             "/truly_inspirational_quote package_with_interfaces/msg/AmazingQuote"], cwd=built_solutions, env=ros_env, capture_output=True, text=True,
            timeout=60, stdin=subprocess.DEVNULL, start_new_session=True, check=False)
        assert echo.returncode == 0, echo.stderr
        assert "philosopher_name: Tyler" in echo.stdout
    finally:
        report = launch.stop(sigint_timeout=10.0)
    assert report.signal_used == "SIGINT" and report.returncode == 0, launch.stderr()


@pytest.mark.timeout(600)
def test_an_rclcpp_node_is_graded_by_the_print_forever_checks(tmp_path):
    from ros2course.grade.engine import grade_lesson  # noqa: PLC0415
    from ros2course.lesson.catalog import Lesson  # noqa: PLC0415

    package = Path(__file__).parents[1] / "solutions" / "src" / "cpp_package_with_a_node"
    shutil.copytree(package, tmp_path / "src" / package.name)
    lesson = Lesson(id="cpp-node", title="A C++ node that prints forever", chapters=[25, 26],
                    requires=["rclcpp", "colcon", "cmake", "cxx"], packages=["cpp_package_with_a_node"],
                    instructions=textwrap.dedent("The seed's C++ print_forever_node (test lesson)."),
                    hints=["rclcpp::Node", "create_wall_timer", "RCLCPP_INFO"], grader="cpp_node")
    result = grade_lesson(lesson, tmp_path)
    failed = [f"{c.id}: {c.observed} (expected {c.expected})" for c in result.checks if not c.passed]
    assert result.status == "passed", result.message + "\n" + "\n".join(failed)
    assert {c.id for c in result.checks} >= {"node_name", "log_format", "counts_from_zero", "rate", "sigint_exit"}
