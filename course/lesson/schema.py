"""The schema of ``lesson.yaml``: pydantic models that validate a lesson when the catalog loads it.

A malformed lesson is reported as ``<file>: <field>: <what is wrong>`` (pydantic's
error locations, :func:`format_validation_error`). What validation yields are the
plain values :mod:`ros2course.lesson.catalog` builds its :class:`~ros2course.lesson.catalog.Lesson`
and its parts from (this module imports nothing of it): a warm ``check`` loads them from the kept catalog without importing
pydantic at all (about 50 ms of every check before the learner's node starts, issue 36).
Each model here mirrors one of those classes field for field; a test keeps the two in step.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, ValidationInfo, field_validator, model_validator

from ros2course.lesson import ID_PATTERN as _ID
from ros2course.ros.requirements import KNOWN_REQUIREMENTS


class ReferenceSolutionSchema(BaseModel):
    """The schema of :class:`~ros2course.lesson.catalog.ReferenceSolution` (its fields and what each accepts)."""

    model_config = ConfigDict(extra="forbid")

    #: Shell commands run in the workspace before grading (what the learner types).
    commands: list[str] = Field(default_factory=list)


#: A fully qualified ROS name (``/amazing_quote``, ``/ns/node``): what the graph shows.
_ROS_NAME = r"^(/[A-Za-z_][A-Za-z0-9_]*)+$"
#: An interface type as the graph spells it (``package_with_interfaces/msg/AmazingQuote``).
_TYPE_NAME = r"^[A-Za-z][A-Za-z0-9_]*/(msg|srv|action)/[A-Z][A-Za-z0-9]*$"


class GraphNodeSchema(BaseModel):
    """The schema of :class:`~ros2course.lesson.catalog.GraphNode` (its fields and what each accepts)."""

    model_config = ConfigDict(extra="forbid")

    name: Annotated[str, Field(pattern=_ROS_NAME)]
    part: str = ""


#: The roles an endpoint of the contract can have, per list of :class:`LessonGraphSchema` (``ros2 node info``'s sections).
_ROLES = {"topics": ("publish", "subscribe"), "services": ("serve", "call")}


class GraphEndpointSchema(BaseModel):
    """The schema of :class:`~ros2course.lesson.catalog.GraphEndpoint` (its fields and what each accepts)."""

    model_config = ConfigDict(extra="forbid")

    name: Annotated[str, Field(pattern=_ROS_NAME)]
    type: Annotated[str, Field(pattern=_TYPE_NAME)]
    role: Literal["publish", "subscribe", "serve", "call", ""] = ""
    part: str = ""


class LessonGraphSchema(BaseModel):
    """The schema of :class:`~ros2course.lesson.catalog.LessonGraph` (its fields and what each accepts)."""

    model_config = ConfigDict(extra="forbid")

    nodes: list[GraphNodeSchema] = Field(default_factory=list)
    topics: list[GraphEndpointSchema] = Field(default_factory=list)
    services: list[GraphEndpointSchema] = Field(default_factory=list)

    @model_validator(mode="after")
    def _roles_fit(self) -> LessonGraphSchema:
        """Each list's default role filled in; a topic's role is a topic role, a service's a service role."""
        for field, roles in _ROLES.items():
            kind = "msg" if field == "topics" else "srv"
            for end in getattr(self, field):
                if not end.role:
                    end.role = roles[0]
                if end.role not in roles:
                    raise ValueError(f"{field[:-1]} {end.name}: role {end.role!r} is not one of {', '.join(roles)}")
                if f"/{kind}/" not in end.type:
                    raise ValueError(f"{field[:-1]} {end.name}: type {end.type} is not a {kind} type")
        return self



class LessonSchema(BaseModel):
    """The schema of :class:`~ros2course.lesson.catalog.Lesson` (its fields and what each accepts)."""

    model_config = ConfigDict(extra="forbid")

    id: Annotated[str, Field(pattern=_ID)]
    title: Annotated[str, Field(min_length=3)]
    beyond: str = ""
    chapters: list[int] = Field(default_factory=list)
    requires: list[str] = Field(default_factory=list)
    packages: list[str] = Field(default_factory=list)
    instructions: Annotated[str, Field(min_length=20)]
    hints: list[Annotated[str, Field(min_length=5)]] = Field(min_length=3)
    grader: Annotated[str, Field(pattern=r"^[a-z_][a-z0-9_]*$")]
    starter: str = "starter"
    starter_includes: list[Annotated[str, Field(pattern=_ID)]] = Field(default_factory=list)
    reference: ReferenceSolutionSchema = Field(default_factory=ReferenceSolutionSchema)
    interfaces: list[Annotated[str, Field(pattern=r"^[a-z][a-z0-9_]*$")]] = Field(default_factory=list)
    references: list[Annotated[str, Field(pattern=r"^[a-z][a-z0-9_]*$")]] = Field(default_factory=list)
    folders: list[Annotated[str, Field(pattern=r"^[A-Za-z0-9_][A-Za-z0-9_./-]*$")]] = Field(default_factory=list)
    starter_solutions: list[Annotated[str, Field(pattern=r"^src/[A-Za-z0-9_]+(/[A-Za-z0-9_][A-Za-z0-9_.-]*)*$")]] = (
        Field(default_factory=list))
    graph: LessonGraphSchema | None = None


    @field_validator("chapters")
    @classmethod
    def _chapters_or_beyond(cls, chapters: list[int], info: ValidationInfo) -> list[int]:
        if not chapters and not str(info.data.get("beyond") or "").strip():
            raise ValueError("give at least 1 seed tutorial chapter, or `beyond:` naming where the subject of a "
                             "lesson the tutorial has no chapter for is documented")
        return chapters

    @field_validator("requires")
    @classmethod
    def _known_requirements(cls, value: list[str]) -> list[str]:
        unknown = [name for name in value if name not in KNOWN_REQUIREMENTS]
        if unknown:
            raise ValueError(f"unknown requirement(s) {unknown}; known: {list(KNOWN_REQUIREMENTS)}")
        return value


def format_validation_error(path, error: ValidationError) -> str:
    """One line per problem: ``file: field: message``."""
    lines = []
    for item in error.errors():
        field = ".".join(str(part) for part in item["loc"]) or "(top level)"
        lines.append(f"{path}: {field}: {item['msg']}")
    return "; ".join(lines)


def validate_lesson(data: dict) -> dict:
    """``data`` (a parsed ``lesson.yaml``) validated, as plain values: every field of
    :class:`~ros2course.lesson.catalog.Lesson` that YAML gives, defaults filled in, the graph's roles set.

    Raises:
        pydantic.ValidationError: a schema violation (see :func:`format_validation_error`).
    """
    return LessonSchema.model_validate(data).model_dump()


def validate_graph(data: dict) -> dict:
    """``data`` (a lesson's ``graph:`` mapping) validated, as plain values (roles set).

    Raises:
        pydantic.ValidationError: a schema violation.
    """
    return LessonGraphSchema.model_validate(data).model_dump()
