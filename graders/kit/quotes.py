"""Shared by the parameters, launch-files and param-dump-load graders (seed ch. 22 and 24).

Contract names come from shared/LESSONS.md; the launch file's values from the
seed's ch. 22.9 listing.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from course.grading import GradingSession

PACKAGE = "python_package_that_uses_parameters_and_launch_files"
EXECUTABLE = "amazing_quote_configurable_publisher_node"
NODE = "amazing_quote_configurable_publisher_node"
INTERFACES = "package_with_interfaces"

#: Parameters the node declares and their defaults (seed ch. 22.3).
DEFAULTS: dict[str, Any] = {
    "quote": "Use the force, Pikachu!",
    "philosopher_name": "Uncle Ben",
    "topic_name": "amazing_quote",
    "period": 0.5,
}

#: The launch file of seed ch. 22.9.
LAUNCH_FILE = "peanut_butter_falcon_quote_publisher_launch.py"
LAUNCH_NODE = "peanut_butter_falcon_quote_publisher_node"
LAUNCH_TOPIC = "truly_inspirational_quote"
LAUNCH_PERIOD = 0.25  # seconds
LAUNCH_PHILOSOPHER = "Tyler"
LAUNCH_QUOTE = ("Yeah, you're gonna die, it's a matter of time. That ain't the question. The question's, "
                "whether they're gonna have a good story to tell about you when you're gone")
LAUNCH_PARAMETERS: dict[str, Any] = {
    "topic_name": LAUNCH_TOPIC,
    "period": LAUNCH_PERIOD,
    "quote": LAUNCH_QUOTE,
    "philosopher_name": LAUNCH_PHILOSOPHER,
}


#: rcl_interfaces/msg/ParameterType values -> the words ``ros2 param describe`` uses.
PARAMETER_TYPES = {0: "not set", 1: "boolean", 2: "integer", 3: "double", 4: "string", 5: "byte array",
                   6: "boolean array", 7: "integer array", 8: "double array", 9: "string array"}


def amazing_quote(s: GradingSession) -> type:
    """The workspace's ``package_with_interfaces/msg/AmazingQuote`` class (NotGradable if not built)."""
    return s.interface_type(INTERFACES, "msg", "AmazingQuote")


def short(text: str, limit: int = 70) -> str:
    """``text`` quoted, cut to ``limit`` characters."""
    return repr(text if len(text) <= limit else text[:limit - 3] + "...")


def first_difference(got: str, wanted: str) -> str:
    """Where ``got`` first differs from ``wanted``, e.g. ``differs at character 73: '...question.The'``."""
    if got == wanted:
        return "identical"
    index = len(os.path.commonprefix([got, wanted]))
    start = max(0, index - 15)
    return (f"differs from character {index + 1}: got {got[start:index + 15]!r}, "
            f"expected {wanted[start:index + 15]!r}")


def python_type_name(value: Any) -> str:
    """The ROS parameter type a YAML/Python value maps to (as rclpy's ``Parameter`` infers it)."""
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "double"
    if isinstance(value, str):
        return "string"
    if isinstance(value, (list, tuple)):
        if all(isinstance(v, bool) for v in value):
            return "boolean array"
        if all(isinstance(v, int) and not isinstance(v, bool) for v in value):
            return "integer array"
        if all(isinstance(v, float) for v in value):
            return "double array"
        if all(isinstance(v, str) for v in value):
            return "string array"
    return f"unsupported ({type(value).__name__})"


def parameter_value(value_msg: Any) -> tuple[str, Any]:
    """``(type word, Python value)`` of an ``rcl_interfaces/msg/ParameterValue``."""
    from rclpy.parameter import parameter_value_to_python  # noqa: PLC0415

    kind = PARAMETER_TYPES.get(value_msg.type, f"type {value_msg.type}")
    try:
        value = parameter_value_to_python(value_msg)
    except RuntimeError:
        value = None
    if isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
        value = list(value)
    return kind, value


def topics_seen(s: GradingSession, graph=None) -> str:
    """``/a (pkg/msg/T), /b (...)`` for the learner's topics in ``graph`` (default ``s.ros``; ROS's own left out)."""
    hidden = {"/rosout", "/parameter_events"}
    topics = {name: types for name, types in (graph or s.ros).topic_types().items() if name not in hidden}
    return ", ".join(f"{name} ({', '.join(types)})" for name, types in sorted(topics.items())) or "none"


def package_source(s: GradingSession) -> Path | None:
    """The learner's ``src/.../python_package_that_uses_parameters_and_launch_files`` folder, if any."""
    from course.build import find_packages  # noqa: PLC0415

    found = find_packages(s.workspace_root / "src").get(PACKAGE)
    return found[0] if found else None


def package_share(s: GradingSession) -> Path | None:
    """``share/<package>`` of the installed package, found the way ``ros2 launch`` finds it."""
    return s.find_share(PACKAGE)
