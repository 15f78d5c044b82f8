"""A recording of what a check observed on the ROS graph: one MCAP file per check.

Every message a probe of the grader received (topics, ``/rosout``, service
requests and responses the grader's servers and clients exchanged) is written
as ROS 2 does it (rosbag2's MCAP storage): the channel's schema is the
``ros2msg`` definition text (the type's ``.msg`` file followed by those of the
types it uses, each after a ``MSG: pkg/Type`` line), the message is its CDR
serialization (``rclpy.serialization.serialize_message``), ``log_time`` is when
the grader received it and ``publish_time`` the publisher's DDS send stamp, so
a rate can be recomputed exactly as the grader judged it (on send stamps).
At the end the engine adds a metadata record ``ros2course.checks``: for each
check, its verdict and the wall-clock window (nanoseconds) it judged.

The file opens in Foxglove, in ``ros2 bag info``/``play`` (rosbag2_storage_mcap),
and in ``ros2course evidence``. MCAP spec: https://mcap.dev/spec; ros2msg:
https://mcap.dev/spec/registry#ros2msg.
"""

from __future__ import annotations

import importlib
import re
import threading
import time
from pathlib import Path
from typing import Any


#: The recording's file name inside the check's log folder.
FILE_NAME = "observed.mcap"
#: Metadata record holding the checks' windows (JSON per check id).
CHECKS_METADATA = "ros2course.checks"
#: Separator between the definitions of a ros2msg schema (the MCAP registry's, as rosbag2 writes it).
SEPARATOR = "=" * 80
_PRIMITIVES = {"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32",
               "uint32", "int64", "uint64", "string", "wstring"}


def type_name(msg_type: type) -> str:
    """``pkg/msg/Type`` of a generated rclpy message class (``sensor_msgs.msg._joint_state.JointState``).

    Service halves are named ``pkg/srv/Type_Request`` / ``_Response`` (as rosbag2 names service events' types).
    """
    package, kind = msg_type.__module__.split(".")[:2]
    return f"{package}/{kind}/{msg_type.__name__}"


def _definition_file(msg_type: type) -> Path | None:
    """The ``.msg``/``.srv`` file installed with the class: ``<prefix>/share/<pkg>/<kind>/<Type>.<kind>``.

    Generated Python lives in ``<prefix>/lib/pythonX.Y/site-packages/<pkg>/<kind>/``
    (colcon installs and the PyPI wheels alike), so the prefix is above ``lib``.
    """
    module = importlib.import_module(msg_type.__module__)
    parts = Path(module.__file__).resolve().parts
    if "lib" not in parts:
        return None
    prefix = Path(*parts[:len(parts) - 1 - parts[::-1].index("lib")])
    package, kind = msg_type.__module__.split(".")[:2]
    name = re.sub(r"_(Request|Response)$", "", msg_type.__name__)
    path = prefix / "share" / package / kind / f"{name}.{kind}"
    return path if path.is_file() else None


def _service_half(text: str, msg_type: type) -> str:
    """The request or response part of a ``.srv`` text (split at its ``---`` line)."""
    request, _, response = text.partition("\n---")
    return response.lstrip("-\n") if msg_type.__name__.endswith("_Response") else request


def _nested_types(msg_type: type) -> list[type]:
    """Message classes used by ``msg_type``'s fields (``get_fields_and_field_types``: ``std_msgs/Header``...)."""
    out = []
    for field_type in msg_type.get_fields_and_field_types().values():
        inner = re.sub(r"^sequence<([^,>]+).*>$", r"\1", field_type)
        inner = re.sub(r"\[\d*\]$", "", inner)
        if "/" not in inner:
            continue
        package, name = inner.split("/")[0], inner.split("/")[-1]
        out.append(getattr(importlib.import_module(f"{package}.msg"), name))
    return out


def ros2msg_schema(msg_type: type) -> str:
    """The ``ros2msg`` schema text of ``msg_type``: its definition, then each nested type's after ``MSG:``.

    Raises:
        LookupError: a definition file is not installed beside the generated code.
    """
    seen: dict[str, str] = {}
    order: list[type] = [msg_type]
    while order:
        current = order.pop(0)
        name = type_name(current)
        if name in seen:
            continue
        path = _definition_file(current)
        if path is None:
            raise LookupError(f"no definition file installed for {name}")
        text = path.read_text(encoding="utf-8")
        if path.suffix == ".srv":
            text = _service_half(text, current)
        seen[name] = text.strip() + "\n"
        order.extend(_nested_types(current))
    names = list(seen)
    parts = [seen[names[0]]]
    for name in names[1:]:
        package, _, short = name.split("/")
        parts.append(f"{SEPARATOR}\nMSG: {package}/{short}\n{seen[name]}")
    return "".join(parts)


class Recorder:
    """Writes one check's observations into an MCAP file (thread-safe: probe callbacks run on executor threads).

    Args:
        path: the file to create (``<log_dir>/observed.mcap``).

    A message whose type has no installed definition is recorded under an
    empty schema (``ros2 bag`` cannot decode it; the grade is unaffected):
    recording never changes a verdict.
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self._lock = threading.Lock()
        self._file = path.open("wb")
        self._started: Any = None  # the mcap Writer, made on first use (:meth:`_writer`)
        self._schemas: dict[type, int] = {}
        self._channels: dict[tuple[int, str, type], int] = {}
        self._sequence = 0
        self._closed = False
        #: wall-clock nanoseconds of the first and last message written
        self.first_ns: int | None = None
        self.last_ns: int | None = None

    @property
    def _writer(self) -> Any:
        """The file's ``mcap.writer.Writer``, started on first use (with the lock held): mcap's import
        (10 ms) then happens while a check waits for its nodes, not before it starts them (issue 36)."""
        if self._started is None:
            from mcap.writer import CompressionType, Writer  # noqa: PLC0415 - see the docstring

            self._started = Writer(self._file, compression=CompressionType.ZSTD)
            self._started.start(profile="ros2", library="ros2course")
        return self._started

    def _channel(self, graph: int, topic: str, msg_type: type) -> int:
        key = (graph, topic, msg_type)
        if key not in self._channels:
            if msg_type not in self._schemas:
                try:
                    schema = ros2msg_schema(msg_type).encode()
                    encoding = "ros2msg"
                except (LookupError, ImportError, OSError, ValueError):
                    schema, encoding = b"", ""
                self._schemas[msg_type] = self._writer.register_schema(type_name(msg_type), encoding, schema)
            self._channels[key] = self._writer.register_channel(
                topic, "cdr", self._schemas[msg_type], metadata={"domain_id": str(graph)})
        return self._channels[key]

    def write(self, graph: int, topic: str, msg: Any, publish_ns: int | None = None,
              log_ns: int | None = None) -> None:
        """Record ``msg`` seen on ``topic`` in the graph of domain ``graph``.

        Args:
            publish_ns: the publisher's send stamp (ns since the epoch); default: ``log_ns``.
            log_ns: when the grader received it (ns since the epoch); default: now.
        """
        from rclpy.serialization import serialize_message  # noqa: PLC0415 - only a grading process records

        log_ns = log_ns or time.time_ns()
        data = serialize_message(msg)
        with self._lock:
            if self._closed:
                return
            channel = self._channel(graph, topic, type(msg))
            self._sequence += 1
            self._writer.add_message(channel, log_time=log_ns, data=data, publish_time=publish_ns or log_ns,
                                     sequence=self._sequence)
            self.first_ns = log_ns if self.first_ns is None else min(self.first_ns, log_ns)
            self.last_ns = log_ns if self.last_ns is None else max(self.last_ns, log_ns)

    def metadata(self, name: str, values: dict[str, str]) -> None:
        """Add a metadata record (string keys and values)."""
        with self._lock:
            if not self._closed:
                self._writer.add_metadata(name, values)

    def close(self) -> None:
        """Finish the file (summary and index); later writes are dropped."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            self._writer.finish()
            self._file.close()
