"""Run a learner's Python launch file with the real ``launch_ros``; read it statically for feedback.

* **run**: the launch file is run in a subprocess the way ``ros2 launch`` runs
  it (ros2launch's ``launch_a_launch_file``: a ``LaunchService`` including the
  file through ``AnyLaunchDescriptionSource``), started and stopped like every
  learner process (``Session.launch``: ros2course.run.process.LearnerProcess,
  SIGINT like Ctrl+C). ``launch``/``launch_ros`` come from a sourced system ROS
  or from the source-built underlay (course/ros/underlay.py); the verdict is what
  that real launch started.
* **read**: the file is also parsed with :mod:`ast`, never executed, to say in
  the feedback which ``Node(...)`` actions it holds (their *literal* keyword
  arguments; anything else is reported as not literal, never guessed). The
  same reader gives the sas grader the seed's launch parameters.
* :func:`start_node_action` starts one ``Node`` action with the command line
  launch_ros gives it (``--ros-args -r __node:=NAME -r __ns:=NS --params-file
  TMP.yaml -r FROM:=TO``, the parameters file written with ``yaml.dump({FQN:
  {"ros__parameters": {...}}}, default_flow_style=False)``; shared/ROS_ENV.md,
  launch_ros/actions/node.py): graders use it for their own harness (a node
  started with known parameters), never to stand in for a learner's launch file.
"""

from __future__ import annotations

import ast
import dataclasses
import sys
import time
from pathlib import Path
from typing import Any

import yaml

from ros2course.grade.checklist import Unmet
from ros2course.ros.env import probe_requirement, require
from ros2course.kit.nodes import process_state

MODE_LAUNCH_ROS = "run with launch_ros"

#: Keyword arguments of launch_ros ``Node`` that change how the process is started and
#: that the static reader reproduces.
_STARTING_KWARGS = ("package", "executable", "name", "namespace", "parameters", "remappings",
                    "arguments", "ros_arguments")
#: Keyword arguments that only change how launch shows or supervises the process; accepted and ignored
#: (``output`` is checked first: a value launch refuses ends the whole launch, see :func:`_output_refused`).
_IGNORED_KWARGS = ("output", "emulate_tty", "exec_name", "respawn", "respawn_delay", "sigterm_timeout",
                   "sigkill_timeout", "log_cmd", "output_format")

#: What the subprocess runs in launch_ros mode: ros2launch's launch_a_launch_file, minus the CLI.
_LAUNCH_SCRIPT = """\
import sys
import launch
from launch.actions import IncludeLaunchDescription
from launch.launch_description_sources import AnyLaunchDescriptionSource

service = launch.LaunchService(argv=[], noninteractive=True)
service.include_launch_description(launch.LaunchDescription([
    IncludeLaunchDescription(AnyLaunchDescriptionSource(sys.argv[1])),
]))
sys.exit(service.run())
"""


@dataclasses.dataclass
class NodeAction:
    """One ``Node(...)`` call found in a launch file, with its literal arguments.

    Attributes:
        line: line number of the call in the launch file.
        package, executable, name, namespace: the literal strings (None when not given).
        parameters: the ``parameters=[...]`` elements in order: dicts (nested dicts
            flattened to dotted names, as launch_ros does) or parameter-file paths (str).
        remappings: ``(from, to)`` pairs.
        arguments: ``arguments=[...]`` (before ``--ros-args``).
        ros_arguments: ``ros_arguments=[...]`` (after their own ``--ros-args``).
        unsupported: one sentence per argument that is not a literal of the right shape.
        refused: one sentence per literal argument that launch itself refuses when it runs the action (the
            whole launch then ends with an error, every node of the file with it); :func:`read_launch_file`
            lists them in :attr:`StaticLaunch.problems` too.
    """

    line: int
    package: str | None = None
    executable: str | None = None
    name: str | None = None
    namespace: str | None = None
    parameters: list[dict[str, Any] | str] = dataclasses.field(default_factory=list)
    remappings: list[tuple[str, str]] = dataclasses.field(default_factory=list)
    arguments: list[str] = dataclasses.field(default_factory=list)
    ros_arguments: list[str] = dataclasses.field(default_factory=list)
    unsupported: list[str] = dataclasses.field(default_factory=list)
    refused: list[str] = dataclasses.field(default_factory=list)

    @property
    def supported(self) -> bool:
        """True when every argument was literal and package/executable are known."""
        return not self.unsupported and bool(self.package) and bool(self.executable)

    def fully_qualified_name(self) -> str | None:
        """``/ns/name`` (``/name`` without namespace), or None when the launch file gives no name."""
        if not self.name:
            return None
        namespace = (self.namespace or "").strip("/")
        return f"/{namespace}/{self.name}" if namespace else f"/{self.name}"

    def describe(self) -> str:
        """``Node(package=..., executable=..., name=...)`` with the arguments that were given."""
        parts = [f"{key}={getattr(self, key)!r}" for key in ("package", "executable", "name", "namespace")
                 if getattr(self, key) is not None]
        return f"Node({', '.join(parts)}) at line {self.line}"

    def parameter_files(self) -> list[dict[str, Any] | str]:
        """What each ``parameters`` element becomes on the command line.

        A dict becomes the content of a temporary parameters file keyed by the
        node's fully qualified name (``/**`` when the launch file gives no
        name); a string is passed as it is, as a file path.
        """
        key = self.fully_qualified_name() or "/**"
        return [{key: {"ros__parameters": item}} if isinstance(item, dict) else item for item in self.parameters]

    def ros_args(self, param_paths: list[str]) -> list[str]:
        """The arguments launch_ros passes after the executable (``param_paths``: one per parameters element)."""
        args = list(self.arguments)
        if self.ros_arguments:
            args += ["--ros-args", *self.ros_arguments]
        args.append("--ros-args")
        if self.name:
            args += ["-r", f"__node:={self.name}"]
        if self.namespace:
            args += ["-r", f"__ns:={'/' + self.namespace.lstrip('/')}"]
        for path in param_paths:
            args += ["--params-file", path]
        for source, target in self.remappings:
            args += ["-r", f"{source}:={target}"]
        return args


@dataclasses.dataclass
class StaticLaunch:
    """What :func:`read_launch_file` found.

    Attributes:
        path: the launch file read.
        nodes: every ``Node(...)`` call inside ``generate_launch_description``, in source order.
        problems: reasons the file cannot be launched at all (syntax error, no
            ``generate_launch_description``, ``Node`` not imported from ``launch_ros.actions``, an
            argument launch refuses when it runs the action: :attr:`NodeAction.refused`).
        other_calls: names of other calls in ``generate_launch_description`` that
            the static reader does not run (e.g. ``ExecuteProcess``), for the report.
    """

    path: Path
    nodes: list[NodeAction] = dataclasses.field(default_factory=list)
    problems: list[str] = dataclasses.field(default_factory=list)
    other_calls: list[str] = dataclasses.field(default_factory=list)


def _dotted(node: ast.AST) -> str:
    """``a.b.c`` for a Name/Attribute chain, '' otherwise."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        parts.append(node.id)
        return ".".join(reversed(parts))
    return ""


def _node_aliases(tree: ast.Module) -> tuple[set[str], set[str]]:
    """Names bound to ``launch_ros.actions.Node`` and names bound to the modules holding it.

    Returns:
        ``(node_names, module_prefixes)``: e.g. ``{"Node"}`` for ``from launch_ros.actions import Node``,
        and ``{"launch_ros.actions"}`` for ``import launch_ros.actions`` so that
        ``launch_ros.actions.Node`` is recognised.
    """
    names: set[str] = set()
    prefixes: set[str] = set()
    for stmt in ast.walk(tree):
        if isinstance(stmt, ast.ImportFrom) and stmt.module in ("launch_ros.actions", "launch_ros.actions.node"):
            names |= {alias.asname or alias.name for alias in stmt.names if alias.name == "Node"}
        elif isinstance(stmt, ast.ImportFrom) and stmt.module == "launch_ros":
            prefixes |= {f"{alias.asname or alias.name}" for alias in stmt.names if alias.name == "actions"}
        elif isinstance(stmt, ast.Import):
            for alias in stmt.names:
                if alias.name in ("launch_ros", "launch_ros.actions"):
                    prefixes.add("launch_ros.actions" if alias.asname is None else f"{alias.asname}"
                                  + (".actions" if alias.name == "launch_ros" else ""))
    return names, prefixes


def describe_launch_folder(share: Path | None, package: str) -> str:
    """What ``share/<package>/launch`` holds, for a check that did not find a launch file there."""
    if share is None:
        return f"package {package} is not installed"
    if (share / "launch").is_dir():
        return (f"share/{package}/launch holds: "
                + (", ".join(sorted(p.name for p in (share / "launch").iterdir())) or "nothing"))
    return f"share/{package} has no launch folder"


def _literal(value: ast.AST) -> tuple[bool, Any]:
    """``(True, value)`` when ``value`` is a Python literal (implicitly concatenated strings included)."""
    try:
        return True, ast.literal_eval(value)
    except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
        return False, None


def flatten_parameters(params: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested parameter mappings to dotted names, e.g. ``{"a": {"b": 1}}`` -> ``{"a.b": 1}``.

    The rule of launch_ros ``normalize_parameters`` and of ``ros2 param load``
    (rclpy ``_unpack_parameter_dict``).
    """
    flat: dict[str, Any] = {}
    for key, value in params.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(flatten_parameters(value, f"{name}."))
        else:
            flat[name] = value
    return flat


def _is_param_value(value: Any) -> bool:
    """A value a ROS parameter can hold: bool, int, float, str or a list of one of those."""
    if isinstance(value, (bool, int, float, str)):
        return True
    return isinstance(value, (list, tuple)) and all(isinstance(v, (bool, int, float, str)) for v in value)


def _source(path_text: str, node: ast.AST) -> str:
    """The source text of ``node`` (shortened), for messages."""
    text = ast.get_source_segment(path_text, node) or ast.dump(node)
    text = " ".join(text.split())
    return text if len(text) <= 60 else text[:57] + "..."


#: The output configurations launch accepts, as a string (launch.logging._normalize_output_configuration in
#: ros2/launch, the Jazzy pin in ../shared/ros-src) and as a dict's sources and destinations.
OUTPUT_NAMES = ("screen", "log", "both", "own_log", "full")
OUTPUT_SOURCES = ("stdout", "stderr", "both")
OUTPUT_DESTINATIONS = ("screen", "log", "own_log")


def _output_refused(value: ast.AST) -> str | None:
    """Why launch would refuse ``output=value`` when it runs the action (it raises ValueError from
    ``launch.logging.get_output_loggers``, and the launch ends), or None: the value is accepted, or it is no
    literal (a substitution, evaluated only when launch runs)."""
    ok, config = _literal(value)
    if not ok:
        return None
    accepted = "'screen', 'log', 'both', 'own_log' or 'full'"
    if isinstance(config, str):
        return None if config in OUTPUT_NAMES else f"{config!r} is no output launch knows ({accepted})"
    if not isinstance(config, dict):
        return f"{config!r} is no output configuration (a string: {accepted})"
    for source, destinations in config.items():
        if source not in OUTPUT_SOURCES:
            return f"{source!r} is no output source ('stdout', 'stderr' or 'both')"
        if not isinstance(destinations, (str, list, tuple, set)):
            return f"{destinations!r} is no list of output destinations"
        for destination in [destinations] if isinstance(destinations, str) else destinations:
            if destination not in OUTPUT_DESTINATIONS:
                return f"{destination!r} is no output destination ('screen', 'log' or 'own_log')"
    return None


def _node_name_refused(name: str) -> str | None:
    """Why launch_ros would refuse ``Node(name=name)`` when it runs the action, or None.

    launch_ros's ``Node._perform_substitutions`` calls rclpy's ``validate_node_name`` on the name as given
    (an empty name, one with a ``/`` or a ``-``, one that starts with a digit raise InvalidNodeNameException,
    and the launch ends); the rule is rcl's, so rclpy's own function judges it here. Without rclpy (a grader
    module loaded for its checks alone) nothing is refused: the launch, when it runs, says it itself."""
    try:
        from rclpy.exceptions import InvalidNodeNameException  # noqa: PLC0415 - ROS only where a file is read
        from rclpy.validate_node_name import validate_node_name  # noqa: PLC0415 - rclpy only when grading
    except ImportError:
        return None
    try:
        validate_node_name(name)
    except InvalidNodeNameException as exc:
        reason = (str(exc).splitlines() or ["invalid node name"])[0].rstrip(": ")
        return f"launch_ros refuses the node name {name!r} ({reason})"
    return None


def _read_node_call(call: ast.Call, text: str) -> NodeAction:
    action = NodeAction(line=call.lineno)
    if call.args:
        action.unsupported.append(f"line {call.lineno}: positional arguments to Node() are not supported; "
                                  "use keywords (package=..., executable=...)")
    for keyword in call.keywords:
        key = keyword.arg
        where = f"{key}= (line {keyword.value.lineno})"
        if key is None:
            action.unsupported.append(f"line {call.lineno}: **{_source(text, keyword.value)} is not a literal")
            continue
        if key == "output" and (refused := _output_refused(keyword.value)):
            action.refused.append(f"{where}: {refused}: launch raises ValueError and the whole launch ends")
        if key in _IGNORED_KWARGS:
            continue
        if key not in _STARTING_KWARGS:
            action.unsupported.append(f"{where}: the argument {key} is not supported by the static reader")
            continue
        ok, value = _literal(keyword.value)
        if not ok:
            action.unsupported.append(f"{where}: {_source(text, keyword.value)} is not a literal value")
            continue
        if key == "name" and isinstance(value, str) and (refused := _node_name_refused(value)):
            action.refused.append(f"{where}: {refused}: the whole launch ends")
        elif key in ("package", "executable", "name", "namespace"):
            if not isinstance(value, str) or not value:
                action.unsupported.append(f"{where}: expected a non-empty string, got {value!r}")
            else:
                setattr(action, key, value)
        elif key == "parameters":
            if not isinstance(value, (list, tuple)):
                action.unsupported.append(f"{where}: expected a list of dicts or file paths, got {value!r}")
                continue
            for item in value:
                if isinstance(item, dict) and all(isinstance(k, str) for k in item):
                    flat = flatten_parameters(item)
                    bad = [k for k, v in flat.items() if not _is_param_value(v)]
                    if bad:
                        action.unsupported.append(f"{where}: the value of {bad[0]!r} is not a parameter value "
                                                  "(bool, int, float, str or a list of them)")
                    else:
                        action.parameters.append({k: list(v) if isinstance(v, tuple) else v
                                                  for k, v in flat.items()})
                elif isinstance(item, str):
                    action.parameters.append(item)
                else:
                    action.unsupported.append(f"{where}: {item!r} is neither a dict of parameters nor a file path")
        elif key == "remappings":
            pairs = value if isinstance(value, (list, tuple)) else None
            if pairs is None or not all(isinstance(p, (list, tuple)) and len(p) == 2
                                        and all(isinstance(x, str) for x in p) for p in pairs):
                action.unsupported.append(f"{where}: expected a list of (from, to) string pairs, got {value!r}")
            else:
                action.remappings = [(a, b) for a, b in pairs]
        elif key in ("arguments", "ros_arguments"):
            if not isinstance(value, (list, tuple)) or not all(isinstance(x, str) for x in value):
                action.unsupported.append(f"{where}: expected a list of strings, got {value!r}")
            else:
                setattr(action, key, list(value))
    for key in ("package", "executable"):
        if getattr(action, key) is None and not any(u.startswith(f"{key}=") for u in action.unsupported):
            action.unsupported.append(f"line {call.lineno}: Node() has no {key}=")
    return action


def _undefined_names(tree: ast.Module, path: Path) -> list[str]:
    """One problem per name the file uses but never imports or defines (a forgotten
    ``from launch import LaunchDescription``: ``ros2 launch`` ends in a NameError), found by pyflakes,
    which reads the syntax tree and runs nothing (found by ``dev mutate sas-robot-driver``)."""
    from pyflakes import checker, messages  # noqa: PLC0415 - only launch-file graders need it

    found = checker.Checker(tree, filename=str(path))
    return [f"{path.name} line {m.lineno}: name {m.message_args[0]!r} is not defined (not imported: ros2 launch "
            f"would stop with a NameError)" for m in sorted(found.messages, key=lambda m: m.lineno)
            if isinstance(m, messages.UndefinedName)]


def read_launch_file(path: Path) -> StaticLaunch:
    """Parse a Python launch file without running it and collect its literal ``Node`` actions.

    Only :func:`ast.parse` and :func:`ast.literal_eval` touch the file's text:
    no import, no ``exec``, so nothing the file would do when run happens.

    Args:
        path: the launch file (``*_launch.py``).

    Returns:
        a :class:`StaticLaunch`; never raises for problems of the file (they go to ``problems``).
    """
    found = StaticLaunch(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        found.problems.append(f"cannot read {path.name}: {exc}")
        return found
    try:
        tree = ast.parse(text, filename=str(path))
    except SyntaxError as exc:
        found.problems.append(f"{path.name} line {exc.lineno}: syntax error: {exc.msg}")
        return found
    functions = [f for f in tree.body if isinstance(f, ast.FunctionDef) and f.name == "generate_launch_description"]
    if not functions:
        found.problems.append(f"{path.name} defines no generate_launch_description() function at module level")
        return found
    found.problems += _undefined_names(tree, path)
    node_names, prefixes = _node_aliases(tree)
    for call in ast.walk(functions[-1]):
        if not isinstance(call, ast.Call):
            continue
        name = _dotted(call.func)
        is_node = name in node_names or any(name == f"{prefix}.Node" for prefix in prefixes)
        if not is_node and name.split(".")[-1] == "Node":
            found.problems.append(f"line {call.lineno}: {name}(...) is called but Node is not imported "
                                  "from launch_ros.actions")
            continue
        if is_node:
            action = _read_node_call(call, text)
            found.nodes.append(action)
            found.problems += [f"line {call.lineno}: Node(...) {why}" for why in action.refused]
        elif name and name.split(".")[-1] != "LaunchDescription":
            found.other_calls.append(f"{name}(...) at line {call.lineno}")
    found.nodes.sort(key=lambda n: n.line)
    return found


@dataclasses.dataclass
class LaunchRun:
    """A launch file started with launch_ros.

    Attributes:
        mode: :data:`MODE_LAUNCH_ROS`.
        processes: the launch service process (one element).
        static: what the static reader found in the file, for feedback only.
    """

    mode: str
    processes: list[Any]
    static: StaticLaunch | None = None

    def any_running(self) -> bool:
        """True while at least one of the processes is still running."""
        return any(p.poll() is None for p in self.processes)

    def summary(self) -> str:
        """One sentence: how the file was run."""
        return self.mode

    def file_contents(self) -> str:
        """What the static reader saw in the file, one sentence (for feedback when launch started too little)."""
        if self.static is None:
            return ""
        parts = []
        if self.static.nodes:
            parts.append("its Node actions: " + "; ".join(
                n.describe() + (f" ({'; '.join(n.unsupported)})" if n.unsupported else "") for n in self.static.nodes))
        if self.static.problems:
            parts.append("; ".join(self.static.problems))
        if not parts:
            others = self.static.other_calls
            parts.append("no Node(...) action found in generate_launch_description()"
                         + (f" (other calls: {', '.join(others[:3])})" if others else ""))
        return "the file read statically: " + "; ".join(parts)


def launch_ros_available() -> bool:
    """True when ROS 2's ``launch`` and ``launch_ros`` import (not PyPI's unrelated ``launch``)."""

    return probe_requirement("launch")[0]


def start_node_action(s: Any, action: NodeAction, label: str) -> tuple[Any | None, str]:
    """Start one literal ``Node`` action the way launch_ros does.

    Args:
        s: the :class:`~ros2course.grade.session.Session`.
        action: a supported :class:`NodeAction`.
        label: name for the process's log files.

    Returns:
        ``(process, "")``, or ``(None, reason)`` when the executable is not found.
    """

    path, observed = s.find_executable(action.package, action.executable)
    if path is None:
        return None, f"{action.describe()}: {observed}"
    param_paths = []
    for index, item in enumerate(action.parameter_files()):
        if isinstance(item, dict):
            params_file = s.log_dir / f"{label}.params_{index}.yaml"
            params_file.write_text(yaml.dump(item, default_flow_style=False), encoding="utf-8")
            param_paths.append(str(params_file))
        else:
            param_paths.append(item)
    return s.launch(path, label, action.ros_args(param_paths)), ""


def start_launch_file(s: Any, launch_file: Path, label: str = "launch") -> LaunchRun:
    """Run ``launch_file`` with launch_ros, as ``ros2 launch`` does; read it statically for feedback.

    Args:
        s: the :class:`~ros2course.grade.session.Session` (it starts the process,
            a ros2course.run.process.LearnerProcess, and stops it at its end).
        launch_file: the launch file (normally the installed one in ``share/<pkg>/launch``).
        label: prefix of the log files.

    Returns:
        a :class:`LaunchRun` holding the launch process.

    Raises:
        MissingRequirement: ``launch``/``launch_ros`` are not installed (``ros2course
            doctor --fix`` builds them).
    """
    if not launch_ros_available():

        require(["launch"], f"running {launch_file.name}")
    proc = s.launch(Path(sys.executable), label, ["-c", _LAUNCH_SCRIPT, str(launch_file)])
    try:
        static = read_launch_file(launch_file)
    except Exception:  # noqa: BLE001 - the reader is only feedback; launch itself says what is wrong
        static = None
    return LaunchRun(MODE_LAUNCH_ROS, [proc], static=static)


# --- kit steps over a learner's launch file -------------------------------------------------

def installed_launch_file(s: Any, check_id: str, package: str, name: str, source: Path | None) -> Path:
    """Record ``check_id``: ``share/<package>/launch/<name>`` is installed (found as ``ros2 launch`` finds it).

    Args:
        s: the :class:`~ros2course.grade.session.Session`.
        source: the package's source folder (``src/.../<package>``), if any.

    Returns:
        The file to run: the installed one, else the one in ``source/launch`` (the
        failed check then says setup.py does not install it).

    Raises:
        Unmet: the package has no such launch file at all.
    """

    share = s.find_share(package)
    installed = share / "launch" / name if share else None
    expected = f"install/{package}/share/{package}/launch/{name}"
    if installed is not None and installed.is_file():
        s.record(check_id, True, str(installed.relative_to(s.workspace_root))
                 if installed.is_relative_to(s.workspace_root) else str(installed), expected)
        return installed
    in_source = source / "launch" / name if source else None
    where = describe_launch_folder(share, package)
    if in_source is not None and in_source.is_file():
        s.record(check_id, False, where + f"; src/.../launch/{name} exists but setup.py does not install it "
                 "(the remaining checks run that source file)", expected)
        return in_source
    s.record(check_id, False, where + f"; no launch/{name} in the package's source either", expected,
             f"create launch/{name} in the package and install it from setup.py's data_files")
    raise Unmet(f"there is no {name} to launch")


def launched_node(s: Any, started_id: str, node_id: str, run: LaunchRun, package: str, executable: str,
                  node: str, timeout: float = 10.0) -> bool:
    """Wait for ``node`` started by ``run``; record ``started_id`` (launch started ``package/executable``) and
    ``node_id`` (a node called ``node`` runs). Returns whether the node appeared.

    Waits up to ``timeout`` seconds (launch_ros start-up included), less when
    the launch process ends, or 3 s after other nodes appeared without it
    (launch_ros's own ``launch_ros_<pid>`` node not counted). ``started_id`` is
    judged on launch's own "process started" report or the node being there.

    Raises:
        Unmet: nothing the launch file started is still running.
    """


    began = time.monotonic()
    first_other: list[float] = []

    def give_up() -> bool:
        if not run.any_running():
            return True
        if not first_other and [n for n in s.graph.node_names() if not n.startswith("/launch_ros_")]:
            first_other.append(time.monotonic())
        return bool(first_other) and time.monotonic() - first_other[0] > 3.0

    with s.phase("start"):
        found = s.graph.wait_for_node(node, timeout, abort=give_up)
    proc = run.processes[0]
    output = proc.stdout() + "\n" + proc.stderr()
    expected = f"the launch file starts {package}/{executable}"
    if (f"[{executable}-" in output and "process started" in output) or found:
        s.record(started_id, True, f"{run.mode}: launch started {executable}", expected)
    else:
        tail = " | ".join(output.strip().splitlines()[-3:])
        contents = run.file_contents()
        s.record(started_id, False, f"{run.mode}: launch did not report starting {executable}; "
                 f"{process_state(proc)}" + (f"; last output: {tail}" if tail else "")
                 + (f"; {contents}" if contents else ""), expected)
    seen = ", ".join(s.graph.node_names()) or "none"
    states = "; ".join(f"{p.name}: {process_state(p)}" for p in run.processes)
    s.record(node_id, found, f"node /{node} is running ({run.mode})" if found else
             f"no node named {node} after {time.monotonic() - began:.1f} s; nodes seen: {seen}; {states}",
             f"a node named {node} (Node(name=...) renames the node)")
    if not run.any_running():
        raise Unmet(f"nothing the launch file started is running: {states}")
    return found
