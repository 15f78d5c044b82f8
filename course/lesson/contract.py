"""Contract coverage (issue 37): ``chapters/<folder>/contract.yaml``, every requirement a lesson states.

A lesson's ``contract.yaml`` traces each requirement sentence of its instructions,
hints and contract (``CONTRACT.md`` or its row in shared/LESSONS.md) to the checks
of its grader that fail when the requirement is broken, or says why it is not
graded::

    lesson: qos
    requirements:
      - id: sensor-profile                 # kebab-case, unique in the file
        says: "sensor_publisher_node publishes with the sensor-data profile (BEST_EFFORT, VOLATILE, KEEP_LAST 5)"
        from: instructions                 # instructions | contract | hint
        checks: [sensor_best_effort]       # ids from the grader's CHECKS
      - id: monitor-history-depth
        says: "..."
        from: contract
        not_graded: "the graph carries no remote history depth ..."

:func:`load_contract` reports every problem as ``path:line: message`` (the line from
the YAML node's mark): a requirement with neither or both of ``checks`` and
``not_graded``, a check id the grader does not declare, a duplicate requirement id,
an unknown key, a ``lesson:`` that is not the folder's lesson. The grader's check ids
are passed in (this layer does not import graders: ``ros2course.grade.coverage`` does).
:func:`coverage_markdown` renders ``docs/contract-coverage.md`` from the contracts.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection, Sequence
from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from ros2course.lesson import ID_PATTERN

#: The file name in a lesson's folder.
CONTRACT_FILE = "contract.yaml"
#: Where each requirement's sentence comes from.
SOURCES = ("instructions", "contract", "hint")


@dataclasses.dataclass(frozen=True)
class ContractProblem:
    """One problem of a ``contract.yaml``: printed ``path:line: message``."""

    path: Path
    line: int
    message: str

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: {self.message}"


class Requirement(BaseModel):
    """One requirement the lesson states, and the checks that fail when it is broken (or why none does).

    Attributes:
        id: kebab-case, unique in the file.
        says: the requirement, in the lesson's words or close to them.
        source: where it is stated (``from:`` in YAML): instructions, contract or hint.
        checks: ids of the grader's checks that fail when it is broken; None with ``not_graded``.
        not_graded: why no check judges it (a sentence an instructor would accept); None with ``checks``.
    """

    model_config = ConfigDict(extra="forbid")

    id: Annotated[str, Field(pattern=ID_PATTERN)]
    says: Annotated[str, Field(min_length=3)]
    source: Literal["instructions", "contract", "hint"] = Field(alias="from")
    checks: list[Annotated[str, Field(min_length=1)]] | None = None
    not_graded: str | None = None

    @model_validator(mode="after")
    def _checks_or_not_graded(self) -> Requirement:
        if self.checks is not None and self.not_graded is not None:
            raise ValueError("give either `checks` or `not_graded`, not both")
        if self.checks is None and self.not_graded is None:
            raise ValueError("give `checks` (the check ids that fail when it is broken) or `not_graded` (why none does)")
        if self.checks is not None and not self.checks:
            raise ValueError("`checks` is empty: name the checks that fail, or say why it is `not_graded`")
        if self.not_graded is not None and len(self.not_graded.strip()) < 10:
            raise ValueError("`not_graded` needs a reason (a sentence)")
        return self

    @property
    def graded(self) -> bool:
        """True when checks judge it."""
        return self.checks is not None


class Contract(BaseModel):
    """A lesson's ``contract.yaml``.

    Attributes:
        lesson: the lesson's id (must be the folder's lesson).
        requirements: in the order the lesson states them.
        path: the file; set by the loader, not read from YAML.
    """

    model_config = ConfigDict(extra="forbid")

    lesson: Annotated[str, Field(pattern=ID_PATTERN)]
    requirements: list[Requirement] = Field(min_length=1)
    path: Path = Field(default=Path(CONTRACT_FILE), exclude=True)

    @property
    def mapped(self) -> list[Requirement]:
        """Requirements some check judges."""
        return [r for r in self.requirements if r.graded]

    @property
    def not_graded(self) -> list[Requirement]:
        """Requirements no check judges (each with its reason)."""
        return [r for r in self.requirements if not r.graded]


def _line(node: yaml.Node | None) -> int:
    return node.start_mark.line + 1 if node is not None else 1


def _child(node: yaml.Node, key: Any) -> tuple[yaml.Node | None, yaml.Node | None]:
    """``(key node, value node)`` of ``key`` in a mapping node, or ``(None, item node)`` of a sequence."""
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            if isinstance(key_node, yaml.ScalarNode) and key_node.value == str(key):
                return key_node, value_node
    elif isinstance(node, yaml.SequenceNode) and isinstance(key, int) and 0 <= key < len(node.value):
        return None, node.value[key]
    return None, None


def _line_of(root: yaml.Node, loc: Sequence[Any], *, key: bool = False) -> int:
    """The line of the node at ``loc`` (pydantic's error location), or of the deepest node found on the way.

    ``key``: the line of the last mapping key itself (an unknown key), not of its value.
    """
    node, line = root, _line(root)
    for index, part in enumerate(loc):
        key_node, value_node = _child(node, part)
        if value_node is None:
            break
        last = index == len(loc) - 1
        line = _line(key_node if (key and last and key_node is not None) else value_node)
        node = value_node
    return line


def _compose(path: Path, text: str) -> tuple[yaml.Node | None, Any]:
    """The document's node tree (with marks) and its data."""
    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        return node, (loader.construct_document(node) if node is not None else None)
    finally:
        loader.dispose()


def load_contract(path: Path, lesson_id: str, check_ids: Collection[str] | None = None,
                  ) -> tuple[Contract | None, list[ContractProblem]]:
    """Load ``path`` (a lesson's ``contract.yaml``) and every problem found in it.

    Args:
        lesson_id: the lesson of the folder the file is in.
        check_ids: the ids of the lesson's grader's ``CHECKS``; None to skip that comparison.

    Returns:
        ``(contract, problems)``: the contract is None when the file cannot be read or
        violates the schema; problems are in file order.
    """
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        return None, [ContractProblem(path, 1, f"cannot be read: {exc.strerror}")]
    try:
        root, data = _compose(path, text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        return None, [ContractProblem(path, mark.line + 1 if mark is not None else 1, f"not valid YAML: {problem}")]
    if root is None or not isinstance(data, dict):
        return None, [ContractProblem(path, _line(root), "expected a mapping with `lesson:` and `requirements:`")]

    problems: list[ContractProblem] = []
    contract: Contract | None = None
    try:
        contract = Contract.model_validate(data)
        contract.path = path
    except ValidationError as exc:
        for error in exc.errors():
            loc = [part for part in error["loc"] if part not in ("function-after[_checks_or_not_graded()]",)]
            unknown = error["type"] == "extra_forbidden"
            where = ".".join(str(part) for part in loc) or "(top level)"
            message = (f"{where}: unknown key `{loc[-1]}`" if unknown and loc
                       else f"{where}: {error['msg'].removeprefix('Value error, ')}")
            problems.append(ContractProblem(path, _line_of(root, loc, key=unknown), message))

    if isinstance(data.get("lesson"), str) and data["lesson"] != lesson_id:
        problems.append(ContractProblem(path, _line_of(root, ["lesson"]),
                                        f"lesson: {data['lesson']!r} is not this folder's lesson {lesson_id!r}"))
    requirements = data.get("requirements")
    if isinstance(requirements, list):
        seen: dict[str, int] = {}
        for index, item in enumerate(requirements):
            if not isinstance(item, dict):
                continue
            rid = item.get("id")
            if isinstance(rid, str):
                if rid in seen:
                    problems.append(ContractProblem(path, _line_of(root, ["requirements", index, "id"]),
                                                    f"requirements.{index}.id: duplicate requirement id {rid!r} "
                                                    f"(first at line {seen[rid]})"))
                else:
                    seen[rid] = _line_of(root, ["requirements", index, "id"])
            checks = item.get("checks")
            if check_ids is not None and isinstance(checks, list):
                for position, check in enumerate(checks):
                    if isinstance(check, str) and check not in check_ids:
                        problems.append(ContractProblem(
                            path, _line_of(root, ["requirements", index, "checks", position]),
                            f"requirements.{index}.checks: {check!r} is not a check of the lesson's grader"))
    problems.sort(key=lambda p: p.line)
    return (contract if not problems else None), problems


def contract_path(folder: Path) -> Path:
    """Where the contract of the lesson in ``folder`` lives."""
    return folder / CONTRACT_FILE


@dataclasses.dataclass
class LessonCoverage:
    """One lesson's row of the coverage document.

    Attributes:
        lesson: the lesson's id.  folder: its folder's name (``27-qos``).
        contract: its loaded contract, or None (no file, or one with problems).
        problems: what is wrong with its file (none when it is missing).
    """

    lesson: str
    folder: str
    contract: Contract | None
    problems: list[ContractProblem] = dataclasses.field(default_factory=list)


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


def coverage_markdown(rows: Sequence[LessonCoverage]) -> str:
    """``docs/contract-coverage.md``: a summary table, then each traced lesson's requirements."""
    out = ["# Contract coverage", "",
           "Every requirement a lesson states (its instructions, hints and contract) and the checks of its",
           "grader that fail when it is broken, or why none does (issue 37). Made from each lesson's",
           "`chapters/<folder>/contract.yaml` by `ros2course dev contract-coverage --write`; do not edit by hand.",
           "", "| lesson | requirements | mapped | not graded |", "|---|---:|---:|---:|"]
    for row in rows:
        if row.contract is not None:
            c = row.contract
            out.append(f"| [`{row.lesson}`](#{row.lesson}) | {len(c.requirements)} | {len(c.mapped)} | "
                       f"{len(c.not_graded)} |")
        else:
            state = f"{len(row.problems)} problem(s) in contract.yaml" if row.problems else "not yet traced"
            out.append(f"| `{row.lesson}` | {state} | | |")
    traced = [r for r in rows if r.contract is not None]
    total = sum(len(r.contract.requirements) for r in traced if r.contract)
    mapped = sum(len(r.contract.mapped) for r in traced if r.contract)
    out += ["", f"{len(traced)} of {len(rows)} lessons traced: {total} requirements, {mapped} mapped to checks, "
                f"{total - mapped} not graded."]
    for row in traced:
        assert row.contract is not None
        out += ["", f"## {row.lesson}", "", f"`chapters/{row.folder}/{CONTRACT_FILE}`", "",
                "| requirement | says | from | checks / not graded because |", "|---|---|---|---|"]
        for r in row.contract.requirements:
            judged = (", ".join(f"`{c}`" for c in r.checks) if r.checks is not None
                      else f"not graded: {_cell(r.not_graded or '')}")
            out.append(f"| `{r.id}` | {_cell(r.says)} | {r.source} | {judged} |")
    return "\n".join(out) + "\n"
