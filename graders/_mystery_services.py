"""The grader's ``/what_is_the_point`` server for the ``inspect-services`` lesson (tutorial ch. 21; issue 12).

A :class:`~ros2course.kit.mystery.MysteryNode` with a random name serves
``/what_is_the_point`` (the learner's ``package_with_interfaces/srv/WhatIsThePoint``)
and records every request it receives with the response it sent. Each
response is drawn at random (so only a script that really called the server
can print it), following the service-server-client lesson's rule: when the
request's quote contains ``life`` (any case) the point's coordinates sum to
42, otherwise they do not (shared/LESSONS.md, ``service-server-client``).

Coordinates are multiples of 0.25, exactly representable in binary, so
``ros2 service call`` prints them as written here (it prints the response with
``%r``: ``...WhatIsThePoint_Response(point=geometry_msgs.msg.Point(x=12.25, y=3.5, z=26.25))``,
ros2cli ``ros2service/verb/call.py``).

The server also turns on Jazzy's service introspection (contents), so
``ros2 service echo /what_is_the_point`` shows its requests and responses
(rclpy ``Service.configure_introspection``).
"""

from __future__ import annotations

import dataclasses
import random
import threading
from typing import Any

from ros2course.kit import Session
from ros2course.kit.mystery import MysteryNode

_RANDOM = random.SystemRandom()

#: The service's name (shared/LESSONS.md, service-server-client and inspect-services).
SERVICE = "/what_is_the_point"
SERVICE_TYPE = "package_with_interfaces/srv/WhatIsThePoint"
#: The sum of the coordinates for a quote about life (seed ch. 20).
ANSWER = 42.0


@dataclasses.dataclass(frozen=True)
class Call:
    """One request the oracle received and what it answered.

    Attributes:
        quote: the request's ``quote.quote`` text.
        philosopher: the request's ``quote.philosopher_name``.
        quote_id: the request's ``quote.id``.
        point: the response's ``(x, y, z)``.
    """

    quote: str
    philosopher: str
    quote_id: int
    point: tuple[float, float, float]

    @property
    def about_life(self) -> bool:
        """The quote contains ``life`` in any case (the service's rule)."""
        return "life" in self.quote.lower()

    def printed_point(self) -> str:
        """How ``ros2 service call`` prints the response's point: ``Point(x=12.25, y=3.5, z=26.25)``."""
        x, y, z = self.point
        return f"Point(x={x!r}, y={y!r}, z={z!r})"

    def describe(self) -> str:
        """The request in words, for feedback: ``quote 'The meaning of life' (id 7, Douglas)``."""
        return f"quote {self.quote!r} (id {self.quote_id}, {self.philosopher or 'no philosopher'})"


def _quarter(low: float, high: float) -> float:
    """A random multiple of 0.25 in [low, high]."""
    return _RANDOM.randrange(int(low * 4), int(high * 4) + 1) / 4


def random_point(about_life: bool) -> tuple[float, float, float]:
    """A point whose coordinates sum to 42 when ``about_life``, and to at most 30 otherwise (all >= 0)."""
    if about_life:
        x, y = _quarter(1, 20), _quarter(1, 20)
        return x, y, ANSWER - x - y
    return _quarter(0, 10), _quarter(0, 10), _quarter(0, 10)


class PointOracle(MysteryNode):
    """A node ``/oracle_NNN`` of the grader serving :data:`SERVICE` until the part ends.

    Args:
        s: the grading session (the node joins ``s.ros``, the check's domain).
        srv_type: the WhatIsThePoint class (``s.interface_type("package_with_interfaces", "srv", "WhatIsThePoint")``).

    Attributes:
        name: the node's random name (its parameter services, e.g. ``/oracle_417/list_parameters``,
            show in ``ros2 service list``).
    """

    def __init__(self, s: Session, srv_type: type) -> None:
        # no "point" in it: a list filtered with | grep point would keep its services too and pass as the whole
        # list (the independent review of stop 82)
        self.name = f"oracle_{_RANDOM.randrange(100, 1000)}"
        super().__init__(s, self.name, parameter_services=True)
        self._lock = threading.Lock()
        self._calls: list[Call] = []
        self.service = self.node.create_service(srv_type, SERVICE, self._answer)
        self._introspect()

    def _introspect(self) -> None:
        """Let ``ros2 service echo`` show the calls (Jazzy service introspection; best effort)."""
        try:
            from rclpy.qos import qos_profile_system_default  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)
            from rclpy.service_introspection import ServiceIntrospectionState  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)

            self.service.configure_introspection(self.node.get_clock(), qos_profile_system_default,
                                                 ServiceIntrospectionState.CONTENTS)
        except (ImportError, AttributeError):  # an rclpy without introspection: echo shows nothing
            pass

    def _answer(self, request: Any, response: Any) -> Any:
        quote = request.quote
        call = Call(str(quote.quote), str(quote.philosopher_name), int(quote.id),
                    random_point("life" in str(quote.quote).lower()))
        response.point.x, response.point.y, response.point.z = call.point
        with self._lock:
            self._calls.append(call)
        return response

    def calls(self) -> list[Call]:
        """Every request received so far, oldest first."""
        with self._lock:
            return list(self._calls)

    def listed_services(self) -> list[str]:
        """Service names only this oracle's run has, that ``ros2 service list`` prints: the service and one of ours."""
        return [SERVICE, f"/{self.name}/list_parameters"]


__all__ = ["ANSWER", "SERVICE", "SERVICE_TYPE", "Call", "PointOracle", "random_point"]
