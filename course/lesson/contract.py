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
      - id: node-name
        says: "the node is named print_forever (super().__init__('print_forever'))"
        from: contract
        checks: [node_name]
        code:                              # optional: the reference lines that implement it
          - file: "src/*/print_forever_node.py"   # a glob on the workspace-relative path
            line: "super\\(\\).__init__\\("         # a regular expression searched in each line

Which lines of the reference implement a requirement (:func:`implements`) is what keeps
the mutation analysis's triage rules honest (issue 37: a rule of ``mutation.yaml`` may
never cover a line that implements a requirement, :func:`ros2course.dev.mutants.rule_conflicts`).
A requirement with ``code:`` names its lines itself. Without it they are derived
mechanically from what it ``says``: every *code-like term* in the sentence (:func:`says_terms`:
a quoted or backticked span, or a word holding a character prose does not use, ``_ . ( ) / : < > = [ ] { } $``
as in ``self.get_logger().info``, ``package.xml``, ``0.5``, ``<depend>``) marks each reference line that
contains it. The derivation over-approximates (a ``main()`` call under ``if __name__ == '__main__':``
contains ``main()``): the safe direction, since a rule it stops is either narrowed or the requirement
names its lines exactly with ``code:``, a statement reviewed in the contract table. A line that is only a
comment or only a string literal (a docstring) implements nothing (:func:`inert_line`), unless a ``code:``
marker with ``docstrings: true`` marks it (a lesson that asks for docstrings).

:func:`load_contract` reports every problem as ``path:line: message`` (the line from
the YAML node's mark): a requirement with neither or both of ``checks`` and
``not_graded``, a check id the grader does not declare, a duplicate requirement id,
an unknown key, a ``lesson:`` that is not the folder's lesson. The grader's check ids
are passed in (this layer does not import graders: ``ros2course.dev.coverage`` does).
:func:`coverage_markdown` renders ``docs/contract-coverage.md`` from the contracts.
"""

from __future__ import annotations

import dataclasses
import fnmatch
import re
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


class CodeMarker(BaseModel):
    """Reference lines that implement a requirement: ``line`` (a regular expression) in the files ``file`` (a glob).

    Attributes:
        docstrings: the marker also marks lines that are only a comment or a string literal (a requirement
            that asks for docstrings); False: such lines implement nothing (:func:`inert_line`), even when
            ``line`` matches them (a docstring that mentions a marked name).
    """

    model_config = ConfigDict(extra="forbid")

    file: Annotated[str, Field(min_length=1)]
    line: Annotated[str, Field(min_length=1)]
    docstrings: bool = False

    @model_validator(mode="after")
    def _compiles(self) -> CodeMarker:
        try:
            re.compile(self.line)
        except re.error as exc:
            raise ValueError(f"`line` is not a regular expression: {exc}") from exc
        return self

    def marks(self, rel: str, text: str) -> bool:
        """Whether line ``text`` of the workspace file ``rel`` is one of these lines."""
        return fnmatch.fnmatch(rel, self.file) and re.search(self.line, text) is not None


class Requirement(BaseModel):
    """One requirement the lesson states, and the checks that fail when it is broken (or why none does).

    Attributes:
        id: kebab-case, unique in the file.
        says: the requirement, in the lesson's words or close to them.
        source: where it is stated (``from:`` in YAML): instructions, contract or hint.
        checks: ids of the grader's checks that fail when it is broken; None with ``not_graded``.
        not_graded: why no check judges it (a sentence an instructor would accept); None with ``checks``.
        code: the reference lines that implement it (None: derived from ``says``, :func:`implements`).
    """

    model_config = ConfigDict(extra="forbid")

    id: Annotated[str, Field(pattern=ID_PATTERN)]
    says: Annotated[str, Field(min_length=3)]
    source: Literal["instructions", "contract", "hint"] = Field(alias="from")
    checks: list[Annotated[str, Field(min_length=1)]] | None = None
    not_graded: str | None = None
    code: list[CodeMarker] | None = None

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


#: Characters that make a word of a requirement's sentence code (:func:`says_terms`).
_CODE_CHARS = set("_.()/:<>=[]{}$")
_QUOTED = re.compile(r"""(?:^|(?<=[\s(\[=]))(`[^`\n]+`|'[^'\n]+'|"[^"\n]+")(?=$|[\s),.;:\]])""")
#: Comment line starts, per file suffix (and CMakeLists.txt): such a line implements nothing.
_COMMENTS = {".py": ("#",), ".sh": ("#",), ".bash": ("#",), ".cmake": ("#",), ".txt": ("#",), ".yaml": ("#",),
             ".yml": ("#",), ".cfg": ("#", ";"), ".toml": ("#",), ".msg": ("#",), ".srv": ("#",),
             ".action": ("#",), ".cpp": ("//", "/*", "*"), ".hpp": ("//", "/*", "*"), ".h": ("//", "/*", "*"),
             ".c": ("//", "/*", "*"), ".cc": ("//", "/*", "*"), ".xml": ("<!--",)}


def says_terms(says: str) -> list[str]:
    """The code-like terms of a requirement's sentence, in order, each once: quoted or backticked spans
    (without their quotes), and words holding one of ``_ . ( ) / : < > = [ ] { } $`` (surrounding
    punctuation of the sentence stripped), at least 3 characters long.

    ``"the node is named print_forever (super().__init__('print_forever'))"`` gives ``print_forever``,
    ``super().__init__('print_forever')``.
    """
    found: list[str] = []
    for match in _QUOTED.finditer(says):
        found.append(match.group(1)[1:-1].strip())
    for word in says.split():
        before = None
        while word != before:  # the sentence's punctuation around the word, until nothing changes
            before = word
            word = word.strip(",;`'\"")
            word = word.rstrip(".:") if not word.endswith("...") else word
            if word.startswith("(") and word.endswith(")") and word[1:-1].count("(") == word[1:-1].count(")"):
                word = word[1:-1]
            elif word.startswith("(") and word.count("(") > word.count(")"):
                word = word[1:]
            elif word.endswith(")") and word.count(")") > word.count("("):
                word = word[:-1]
        if len(word) >= 3 and any(c in _CODE_CHARS for c in word) and any(c.isalnum() for c in word):
            found.append(word)
    return [t for t in dict.fromkeys(found) if len(t) >= 3]


def inert_line(rel: str, text: str) -> bool:
    """Whether a line implements nothing: blank, only a comment, or (Python) only a string literal (a
    docstring line, or a line inside a triple-quoted docstring is not told apart: only whole-line literals)."""
    stripped = text.strip()
    if not stripped:
        return True
    path = Path(rel)
    starts = _COMMENTS.get(path.suffix.lower(), ("#",) if path.name == "CMakeLists.txt" else ())
    if any(stripped.startswith(s) for s in starts) and not stripped.startswith("#!"):
        return True
    if path.suffix == ".py":
        import ast  # noqa: PLC0415 - only for Python lines

        try:
            node = ast.parse(stripped, mode="eval").body
        except (SyntaxError, ValueError):
            return False
        return isinstance(node, ast.Constant) and isinstance(node.value, str)
    return False


def implements(requirement: Requirement, rel: str, text: str) -> str | None:
    """What makes line ``text`` of the workspace file ``rel`` implement ``requirement``, or None.

    With ``code:``, the marker that marks the line (``code: <glob> /<regex>/``); otherwise the first
    code-like term of ``says`` (:func:`says_terms`) the line contains as a whole (``names `main()```; a call
    ``f()`` also with arguments, ``f(``). A line that is only a comment or a string literal implements
    nothing (:func:`inert_line`), unless a marker with ``docstrings: true`` marks it (a requirement that
    asks for docstrings).
    """
    inert = inert_line(rel, text)
    if requirement.code is not None:
        # the contract names its lines itself; a docstring or comment only with `docstrings: true`
        marker = next((m for m in requirement.code if m.marks(rel, text) and (m.docstrings or not inert)), None)
        return None if marker is None else f"code: {marker.file} /{marker.line}/"
    if inert:
        return None
    term = next((t for t in says_terms(requirement.says) if _term_in(t, text)), None)
    return None if term is None else f"names `{term}`"


def _term_in(term: str, text: str) -> bool:
    """Whether ``text`` holds ``term`` as a whole (``0.1`` is not in ``0.0.1``, ``spin`` not in ``spin_once``); a
    call ``f()`` is also found with arguments (``rclpy.init()`` in ``rclpy.init(args=args)``), and a name after
    a dot (``distance_to_goal`` in ``feedback.distance_to_goal``: an attribute is the name, as used)."""
    forms = [term] + ([term[:-1]] if term.endswith("()") else [])
    for form in forms:
        # a number must not continue one (0.1 in 0.0.1); a name may follow a dot (attribute access)
        before = r"(?<![\w.])" if re.match(r"[\d.]", form) else r"(?<!\w)" if re.match(r"\w", form) else ""
        after = r"(?!\w)" if re.search(r"\w$", form) else ""
        if re.search(before + re.escape(form) + after, text):
            return True
    return False


def requirement_lines(path: Path) -> dict[str, int]:
    """``{requirement id: line of its item in contract.yaml}`` (for messages); {} when unreadable."""
    try:
        root, data = _compose(path, path.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError):
        return {}
    out: dict[str, int] = {}
    items = data.get("requirements") if isinstance(data, dict) else None
    for index, item in enumerate(items if isinstance(items, list) else []):
        if isinstance(item, dict) and isinstance(item.get("id"), str):
            out[item["id"]] = _line_of(root, ["requirements", index])
    return out


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
