r"""Mutation analysis of a lesson's grader (issue 24): mutants of the reference, triage, score.

A *mutant* is the lesson's reference workspace with one of its files replaced by
a copy carrying one small change, made by a maintained mutation tool,
`universalmutator <https://github.com/agroce/universalmutator>`_ (regular-expression
rules: its Python rules with its own trivial-compiler-equivalence check for
``.py`` files, which drops mutants that do not compile or compile to the same
bytecode; its C/C++ rules for C and C++ sources; its universal rules for
scripts, CMake, package.xml and anything else). This module never invents a
mutation of its own. A second *family* of mutants, for held-out samples of
lessons whose universalmutator mutants every earlier sample has already shown
(issue 37), comes from `cosmic-ray <https://github.com/sixty-north/cosmic-ray>`_'s
core operators on the lesson's Python files (:func:`generate_cosmic_ray_mutants`):
another tool's operators (parso syntax trees, not regular expressions), so a
sample of them was never looked at while the rules were written. A third, for
lessons whose cosmic-ray pools are spent too, comes from
`mutmut <https://github.com/boxed/mutmut>`_ 2's mutations of the Python files
(:func:`generate_mutmut_mutants`): strings wrapped in ``XX``, assignments of
``None``, numbers off by one, swapped keywords and operators, dropped arguments.

Each mutant is graded by the lesson's grader (through the batch engine,
:mod:`ros2course.dev.mutate`) and classified (:func:`classify`):

* ``killed``: graded, lost points (the checks it lost are named);
* ``killed by build``: the workspace does not build, so no check ran (C++ mutants that do not
  compile, a CMakeLists.txt or setup.cfg colcon cannot use; a package.xml that is not XML is never
  generated: :func:`invalid_mutant`);
* ``survived``: full marks: the grader did not notice the change;
* ``timed out`` / ``grader error``: neither (reported, never counted as killed).

``chapters/<lesson>/mutation.yaml``, beside ``lesson.yaml``, is the author's
triage of survivors judged equivalent or outside the lesson's contract (issue 37:
triage by rule, decided before it is tested)::

    # optional: which reference files are mutated (globs, workspace-relative);
    # default: the lesson's own files (:func:`lesson_files`)
    files: [src/python_package_with_a_node/python_package_with_a_node/print_forever_node.py]
    rules:                                  # kinds of survivor, applied mechanically (:class:`Rule`)
      - id: docstring-pass
        reason: "a docstring replaced by `pass`: documentation only, no behaviour changes"
        file: "*.py"                        # globs (default: every file)
        original: '^\s*("{3}|''{3}).*("{3}|''{3})\s*$'   # regex searched in the original line
        mutated: '^\s*pass\s*$'              # regex searched in the mutated line
      - id: main-block
        reason: "..."
        block: "^if __name__ == .__main__.:"  # the line or the indented block it opens
      - id: package-metadata
        reason: "..."
        file: "*/package.xml"
        original: '<(description|maintainer|license|url)\b'
        set_aside: true                     # never graded: free text no program reads
      - id: library-case-still-true
        reason: "..."
        original: '^\s*\([^()]*\),\s*$'     # a case of a parametrized test ...
        holds: {names: [a, b, expected], that: "(a + b) ** 2 == expected"}  # ... still true once mutated
      - use: main-guard-string              # a rule of the course's library, as it is there (RULE_LIBRARY)
    survivors:                              # one mutant each, for what no rule covers (:class:`TriageEntry`)
      - file: src/python_package_with_a_node/setup.py
        key: 3f2a9c0d1e4b                   # its identity (Mutant.key); or `line: 12` + original + mutated
        original: "zip_safe=True,"          # for the reader: checked against the key
        mutated: "zip_safe=False,"
        reason: "..."

Rules are applied before entries. An entry names one mutant by its identity, never by line text
alone. A rule may never cover a line that implements a requirement of the lesson's contract
(``contract.yaml``; :func:`rule_conflicts`, with :func:`ros2course.lesson.contract.implements`
saying which lines those are), so the two tables check each other; :func:`triage_problems`
reports such a rule, an entry or rule matching no mutant, and a record made under another
grader fingerprint, each with its file and line.

Score = killed / (generated - killed by build - triaged), over the graded mutants
(a sample when ``--sample`` is given): the *tuned* score, since the triage was written
looking at that sample. A *held-out* sample (:func:`held_out_sample`, ``mutate_lessons(...,
held_out=N)``) is drawn afterwards with another seed from the mutants the first sample did
not take, graded with the rules and entries as they are, never tuned: its uncovered survivors
count against it, and are listed for the author (strengthen the grader, or add a rule that
applies from the next held-out sample on). Both are recorded in ``mutation-score.json``
(``held_out``) and ``mutation-outcomes.json``. Every held-out sample graded under the lesson's
current grader fingerprint is pooled (:func:`pooled_held_out`): a lesson is judged by all of
them together, never by its latest or best one.
"""

from __future__ import annotations

import ast
import contextlib
import copy
import dataclasses
import difflib
import fnmatch
import functools
import hashlib
import importlib.util
import json
import marshal
import math
import operator
import random
import re
import shutil
import subprocess
import sys
import tempfile
import types
import warnings
import xml.etree.ElementTree as ET  # noqa: N817 - the standard alias
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, model_validator
from ros2course.errors import CourseError, LessonFormatError, MissingRequirement
from ros2course.files import atomic_write_text
from ros2course.grade.checklist import STOPPED_SETTLED
from ros2course.grade.results import NOT_CHECKED, LessonResult, Status
from ros2course.lesson.catalog import Lesson, content_root, load_catalog, yaml_error_text
from ros2course.lesson.schema import format_validation_error
from ros2course.lesson.courses import MANIFEST, load_manifest

#: Name of the triage file beside ``lesson.yaml``.
TRIAGE_FILE = "mutation.yaml"
#: The course's library of rules many lessons share, beside the lesson folders (``chapters/mutation-rules.yaml``,
#: ``rules:`` as in a ``mutation.yaml``): a lesson's ``- use: <id>`` takes one as it is written there
#: (:func:`rule_library`), so one kind of equivalent mutant has one reason, not a copy per lesson.
RULE_LIBRARY = "mutation-rules.yaml"
#: The lesson's last mutation score, beside ``lesson.yaml``: written by ``dev mutate``, shown by ``dev validate``.
SCORE_FILE = "mutation-score.json"
#: Every graded mutant's outcome of the lesson's last run, beside its score (:func:`write_score`).
OUTCOMES_FILE = "mutation-outcomes.json"
#: The outcomes of a mutant, in the order the table shows them.
KILLED, KILLED_BY_BUILD, SURVIVED, TIMED_OUT, GRADER_ERROR = (
    "killed", "killed by build", "survived", "timed out", "grader error")
OUTCOMES = (KILLED, KILLED_BY_BUILD, SURVIVED, TIMED_OUT, GRADER_ERROR)
#: universalmutator's language per file suffix; other files get its universal rules only.
LANGUAGES = {".py": "python", ".c": "c", ".h": "c", ".cpp": "cpp", ".cc": "cpp", ".hpp": "cpp"}
#: Languages whose mutants universalmutator itself checks (compiles, drops invalid and duplicate ones).
#: C/C++ cannot be compiled alone (ROS headers): their broken mutants are counted as killed by build.
CHECKED_LANGUAGES = {"python"}
#: Where mutants come from: universalmutator (every sample until issue 37's pools were spent, and every first
#: sample), cosmic-ray, mutmut, poodle and mutpy (held-out samples only: ``--held-out N --family cosmic-ray``,
#: ``mutmut``, ``poodle`` or ``mutpy``).
UNIVERSALMUTATOR, COSMIC_RAY, MUTMUT, POODLE, MUTPY = "universalmutator", "cosmic-ray", "mutmut", "poodle", "mutpy"
FAMILIES = (UNIVERSALMUTATOR, COSMIC_RAY, MUTMUT, POODLE, MUTPY)
#: The module each family's tool is imported as.
_FAMILY_MODULES = {UNIVERSALMUTATOR: "universalmutator", COSMIC_RAY: "cosmic_ray", MUTMUT: "mutmut",
                   POODLE: "poodle", MUTPY: "mutpy"}
#: The pip distribution of each family's tool, where it is not the family's name.
_FAMILY_DISTRIBUTIONS = {MUTPY: "mutpy-pynguin"}
#: Files never mutated: generated, binary or bookkeeping.
_SKIP_PARTS = {"__pycache__", "build", "install", "log", ".git"}
_SKIP_SUFFIXES = {".pyc", ".png", ".jpg", ".gif", ".zip", ".gz", ".so", ".a", ".o", ".mcap", ".db3"}


#: A rule's or requirement's id: kebab-case.
_RULE_ID = r"^[a-z0-9]+(-[a-z0-9]+)*$"
#: Quoted strings of a line ('...', "...", with backslash escapes): what :attr:`Rule.strings_only` compares around.
_STRING = re.compile(r'"(?:[^"\\\n]|\\.)*"|\'(?:[^\'\\\n]|\\.)*\'')


def _regex(value: str | None, name: str) -> str | None:
    if value is not None:
        try:
            re.compile(value)
        except re.error as exc:
            raise ValueError(f"`{name}` is not a regular expression: {exc}") from exc
    return value


def original_lines(mutant: Mutant, originals: dict[str, str] | None = None) -> list[str]:
    """The original file's lines (no newlines) of ``mutant``: rebuilt from its content (a mutant changes
    one line), or read from ``originals`` (``{file: text}``) for a mutant known only by its record."""
    if originals and mutant.file in originals:
        return originals[mutant.file].splitlines()
    if not mutant.content or mutant.line < 1:
        return []
    lines = mutant.content.splitlines()
    above = lines[:mutant.line - 1]
    below = lines[mutant.line:] if mutant.mutated != "" else lines[mutant.line - 1:]
    return [*above, *mutant.original.splitlines(), *below]


def _indent(text: str) -> int:
    return len(text) - len(text.lstrip())


#: A shell loop's body opens at ``do`` and closes at ``done`` (words, outside comments).
_SHELL_DO_DONE = re.compile(r"(?<![\w./-])(do|done)(?![\w./-])")


def _shell_code(text: str) -> str:
    """A shell line without its comment (a ``#!`` line is all comment)."""
    return text.split("#", 1)[0] if not text.lstrip().startswith("#!") else ""


def _shell_do_done(text: str) -> list[str]:
    """The ``do`` and ``done`` words of a shell line, in order, outside its comment: the one reading of a
    loop's span that :func:`_shell_loops_open` and :func:`_shell_no_op` share."""
    return _SHELL_DO_DONE.findall(_shell_code(text))


def _shell_loops_open(lines: list[str]) -> list[str]:
    """The headers of the shell loops still open after ``lines`` (outermost first): each ``do`` opens the
    loop of its line, or of the line above when it stands alone; each ``done`` closes the innermost."""
    headers: list[str] = []
    previous = ""
    for text in lines:
        code = _shell_code(text)
        for word in _shell_do_done(text):
            if word == "do":
                headers.append(text if code.strip() != "do" else previous)
            elif headers:
                headers.pop()
        if code.strip():
            previous = text
    return headers


def in_block(lines: list[str], number: int, header: str, own: bool = True, shell: bool = False) -> bool:
    """Whether line ``number`` (1-based) of ``lines`` lies in the indented block of a line matching ``header``
    (a regex; an enclosing line of smaller indentation, as Python and indented scripts nest), or (``own``)
    matches it itself. A blank line belongs to the block of the line above it.

    ``shell``: the lines are a shell script, where a loop's body is what lies between ``do`` and ``done``
    whatever its indentation (an unindented line inserted in a loop is in it): a line is in the block of an
    open loop whose header matches; other headers are judged by indentation.
    """
    if not 1 <= number <= len(lines):
        return False
    pattern = re.compile(header)
    if own and pattern.search(lines[number - 1]):
        return True
    if shell and any(pattern.search(h) for h in _shell_loops_open(lines[:number - 1])):
        return True
    level = _indent(lines[number - 1]) if lines[number - 1].strip() else None
    for text in reversed(lines[:number - 1]):
        if not text.strip():
            continue
        if level is None:  # a blank line: its block is the next non-blank line's above it
            level = _indent(text) + 1
        if _indent(text) < level:
            if pattern.search(text):
                return True
            level = _indent(text)
            if level == 0:
                return False
    return False


class CaseHolds(BaseModel):
    """A rule's ``holds`` matcher: the names of a parametrized test's case, in order, and what a true case satisfies."""

    model_config = ConfigDict(extra="forbid")

    names: list[str] = Field(min_length=1)
    that: str = Field(min_length=3)
    #: ``that`` parsed once (:func:`case_holds` evaluates it for every mutated line of a sample).
    _that: ast.expr = PrivateAttr()

    @model_validator(mode="after")
    def _parses(self) -> CaseHolds:
        try:
            tree = ast.parse(self.that, mode="eval")
        except SyntaxError as exc:
            raise ValueError(f"`that` is not a Python expression: {exc.msg}") from None
        unknown = sorted({n.id for n in ast.walk(tree) if isinstance(n, ast.Name)} - set(self.names))
        if unknown:
            raise ValueError(f"`that` names {', '.join(unknown)}, which `names` does not list")
        self._that = tree.body
        return self


#: The binary operators :func:`_arithmetic` evaluates.
_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
           ast.Pow: operator.pow}


def _arithmetic(node: Any, values: dict[str, float]) -> float:
    """The value of an expression made of numbers, names in ``values``, unary and binary + - * / ** and a
    single ``==`` (1.0 when both sides agree within 1e-9, else 0.0). Raises ValueError on anything else."""
    if isinstance(node, ast.Constant) and type(node.value) in (int, float):
        return node.value
    if isinstance(node, ast.Name) and node.id in values:
        return values[node.id]
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        value = _arithmetic(node.operand, values)
        return -value if isinstance(node.op, ast.USub) else value
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        left, right = _arithmetic(node.left, values), _arithmetic(node.right, values)
        if isinstance(node.op, ast.Pow) and abs(right) > 64:
            raise ValueError("exponent too large")
        return _BINARY[type(node.op)](left, right)
    if (isinstance(node, ast.Compare) and len(node.ops) == 1 and isinstance(node.ops[0], ast.Eq)):
        left, right = _arithmetic(node.left, values), _arithmetic(node.comparators[0], values)
        return 1.0 if math.isclose(left, right, rel_tol=1e-9, abs_tol=1e-9) else 0.0
    raise ValueError(f"not arithmetic: {type(node).__name__}")


def case_holds(line: str, holds: CaseHolds) -> bool:
    """Whether ``line`` (a mutated line such as ``(0.25, 0.5, 0.5625),``) is a case of ``holds.names`` for
    which ``holds.that`` is true. False for a line that is not such a tuple, or whose arithmetic fails
    (division by zero, overflow, a call, a name)."""
    text = line.strip().removesuffix(",").strip()
    try:
        tree = ast.parse(text, mode="eval").body
        if not isinstance(tree, ast.Tuple) or len(tree.elts) != len(holds.names):
            return False
        values = {name: _arithmetic(element, {}) for name, element in zip(holds.names, tree.elts, strict=True)}
        return _arithmetic(holds._that, values) == 1.0
    except (SyntaxError, ValueError, ArithmeticError, TypeError, RecursionError, MemoryError):
        return False


class Rule(BaseModel):
    r"""A kind of survivor the author judged equivalent or outside the lesson's contract, decided before it is
    tested and applied mechanically: every mutant it matches is triaged with its reason (issue 37).

    A mutant matches when every matcher given holds (at least one besides ``file``):

    * ``file``: globs on the workspace-relative path (default: every file);
    * ``original`` / ``mutated``: regular expressions searched in the original / mutated line;
    * ``block``: a regular expression; the changed line matches it or lies in the indented block of a line
      that does (``"^if __name__ == .__main__.:"``: the ``__main__`` block);
    * ``strings_only``: the change is inside quoted strings only (the line outside them is the same);
    * ``not_block``: a regular expression; the changed line is *not* in the indented block of a line matching it
      (``^\s*(for|while|until)\b``: outside every loop of a script, where a ``break`` is a no-op). Blocks are
      found by indentation (:func:`in_block`), as the course's scripts are written.
    * ``starter_line``: the changed line is one the lesson's starter gives as is, in the same place (a line of
      the reference that :func:`starter_given_lines` pairs with an equal line of the starter's copy of the
      file): the learner never writes it, so a change there is outside what the lesson asks of them, unless
      the contract says otherwise (a rule never covers a line that implements a requirement, so a given line
      the lesson makes a requirement, e.g. a discovery loop the grader runs late, stays counted).

    * ``holds``: ``{names: [a, b, expected], that: "(a + b) ** 2 == expected"}``: the mutated line is a case of
      a parametrized test (a tuple of numbers, written as number literals and arithmetic, one per name) for
      which ``that`` still holds, computed exactly as written (``==`` within 1e-9): the mutant turned one true
      case of the function under test into another true case (:func:`case_holds`). Only arithmetic on the
      case's numbers is evaluated, never a call or a name from the file.

    ``set_aside``: its mutants are set aside before sampling, never graded (free text no program reads),
    so a sample is spent on mutants that count. A rule may never cover a line that implements a requirement
    of the lesson's contract (:func:`rule_conflicts`).
    """

    model_config = ConfigDict(extra="forbid")

    id: str = Field(pattern=_RULE_ID)
    reason: str = Field(min_length=10)
    file: list[str] = Field(default_factory=lambda: ["*"])
    original: str | None = None
    mutated: str | None = None
    block: str | None = None
    strings_only: bool = False
    not_block: str | None = None
    starter_line: bool = False
    holds: CaseHolds | None = None
    set_aside: bool = False
    #: ``{workspace-relative file: the starter's copy's lines}``, set by :func:`load_config` (``starter_line``).
    _starters: dict[str, list[str]] = PrivateAttr(default_factory=dict)

    @model_validator(mode="before")
    @classmethod
    def _one_file(cls, data: Any) -> Any:
        if isinstance(data, dict) and isinstance(data.get("file"), str):
            data = {**data, "file": [data["file"]]}
        return data

    @model_validator(mode="after")
    def _matches_something(self) -> Rule:
        for name in ("original", "mutated", "block", "not_block"):
            _regex(getattr(self, name), name)
        if (self.original is None and self.mutated is None and self.block is None and not self.strings_only
                and not self.starter_line and self.holds is None):
            raise ValueError("a rule needs a matcher besides `file`: `original`, `mutated`, `block`, "
                             "`strings_only`, `starter_line` or `holds` (a whole file is left out with `files:`)")
        return self

    def _file(self, rel: str) -> bool:
        return any(fnmatch.fnmatch(rel, glob) for glob in self.file)

    def covers_line(self, rel: str, lines: list[str], number: int) -> bool:
        """Whether some mutant of line ``number`` of ``rel`` could match: the matchers on the original
        (``file``, ``original``, ``block``, ``not_block``); the mutated line is not known."""
        text = lines[number - 1] if 1 <= number <= len(lines) else ""
        return (self._file(rel) and (self.original is None or re.search(self.original, text) is not None)
                and (self.block is None or in_block(lines, number, self.block))
                and (self.not_block is None or not in_block(lines, number, self.not_block, own=False))
                and (not self.starter_line or self._given(rel, lines, number)))

    def _given(self, rel: str, lines: list[str], number: int) -> bool:
        starter = self._starters.get(rel)
        return starter is not None and number in starter_given_lines(tuple(lines), tuple(starter))

    def matches(self, mutant: Mutant, originals: dict[str, str] | None = None) -> bool:
        """Whether this rule triages ``mutant`` (``originals``: ``{file: text}`` when the mutant has no content)."""
        if not self._file(mutant.file):
            return False
        if self.original is not None and re.search(self.original, mutant.original) is None:
            return False
        if self.mutated is not None and re.search(self.mutated, mutant.mutated) is None:
            return False
        if self.holds is not None and not case_holds(mutant.mutated, self.holds):
            return False
        if self.strings_only and (mutant.original == mutant.mutated or "\n" in mutant.original + mutant.mutated
                                  or _STRING.sub('""', mutant.original) != _STRING.sub('""', mutant.mutated)):
            return False
        # the original file's lines, read once when a test below needs them
        whole_file = functools.cache(lambda: original_lines(mutant, originals))

        if not mutant.original.strip() and mutant.line > 1:
            above = whole_file()[mutant.line - 2:mutant.line - 1]
            if not above or above[0].rstrip().endswith("\\"):
                return False  # the file is not known, or the line lands in a command continued from the line above
        if self.block is not None or self.not_block is not None:
            lines = whole_file()[:mutant.line - 1]
            if len(lines) < mutant.line - 1 or (not lines and mutant.line > 1):
                return False  # the file is not known: no block can be judged
            # the changed line as it sits among the lines above: the original one, or for a line universalmutator
            # inserts (no original line) the inserted one, whose indentation says which block it lands in
            lines.append(mutant.original if mutant.original.strip() else mutant.mutated)
            shell = mutant.file.endswith((".sh", ".bash"))
            if self.block is not None and not in_block(lines, mutant.line, self.block, shell=shell):
                return False
            if self.not_block is not None and in_block(lines, mutant.line, self.not_block, own=False, shell=shell):
                return False
        if self.starter_line:
            whole = whole_file()
            if not whole or not self._given(mutant.file, whole, mutant.line):
                return False  # the file is not known, or the line is the learner's to write
        return True


@functools.lru_cache(maxsize=256)
def starter_given_lines(reference: tuple[str, ...], starter: tuple[str, ...]) -> frozenset[int]:
    """The 1-based numbers of the ``reference`` lines the ``starter`` gives as they are, in the same place:
    those in the blocks :class:`difflib.SequenceMatcher` (no junk heuristic) finds equal in both, compared
    with trailing whitespace removed. A starter line the learner must change (a TODO's line) differs from the
    reference's, so it is never one of them."""
    matcher = difflib.SequenceMatcher(None, [line.rstrip() for line in reference],
                                      [line.rstrip() for line in starter], autojunk=False)
    return frozenset(i + 1 for block in matcher.get_matching_blocks() for i in range(block.a, block.a + block.size))


#: How many mutants with the same file, original and mutated line an entry's key is checked against.
_MAX_LINE_INDEX = 64


class TriageEntry(BaseModel):
    """One survivor no rule covers, judged equivalent or outside the lesson's contract, named by its identity:
    ``key`` (:attr:`Mutant.key`, printed by ``dev mutate``; ``original`` and ``mutated`` may go with it for the
    reader, and must be the lines the key was made of), or ``line`` (the number) with ``original`` and
    ``mutated``. Never by line text alone (issue 37): the text of a line is not one mutant."""

    model_config = ConfigDict(extra="forbid")

    file: str = Field(min_length=1)
    key: str | None = Field(default=None, pattern=r"^[0-9a-f]{12}$")
    line: int | None = Field(default=None, ge=1)
    original: str | None = None
    mutated: str | None = None
    reason: str = Field(min_length=10)

    @model_validator(mode="before")
    @classmethod
    def _not_by_text(cls, data: Any) -> Any:
        if isinstance(data, dict):
            if "every_mutant" in data:
                raise ValueError("'every_mutant' is gone: every mutant of a kind of line is a rule (`rules:`, "
                                 "with an id, a reason and matchers), not an entry")
            if "mutant" in data or isinstance(data.get("line"), str):
                raise ValueError("an entry names one mutant by its identity: `key` (dev mutate prints it), or "
                                 "`line` (its number) with `original` and `mutated`; never by line text alone")
        return data

    @model_validator(mode="after")
    def _identifies(self) -> TriageEntry:
        if self.key is None and (self.line is None or self.original is None or self.mutated is None):
            raise ValueError("an entry names its mutant by `key`, or by `line` (number), `original` and `mutated`")
        if self.key is not None and self.original is not None and self.mutated is not None:
            keys = {Mutant(self.file, 0, self.original, self.mutated, "", 0, i).key for i in range(_MAX_LINE_INDEX)}
            if self.key not in keys:
                raise ValueError(f"key {self.key} is not the key of `original` -> `mutated` in {self.file}: "
                                 "copy both from the mutant's record (mutation-outcomes.json)")
        return self

    def matches(self, mutant: Mutant) -> bool:
        """Whether this entry is about ``mutant``."""
        if self.file != mutant.file:
            return False
        if self.key is not None:
            return self.key == mutant.key
        return (self.line == mutant.line and self.original.strip() == mutant.original.strip()
                and self.mutated.strip() == mutant.mutated.strip())

    def describe(self) -> str:
        """``file key`` or ``file:line 'original' -> 'mutated'``."""
        if self.key is not None:
            return f"{self.file} {self.key}"
        return f"{self.file}:{self.line} {self.original.strip()!r} -> {self.mutated.strip()!r}"


class MutationConfig(BaseModel):
    """A lesson's ``mutation.yaml``: which files to mutate, the rules, and the triaged survivors."""

    model_config = ConfigDict(extra="forbid")

    files: list[str] | None = None
    rules: list[Rule] = Field(default_factory=list)
    survivors: list[TriageEntry] = Field(default_factory=list)

    @model_validator(mode="after")
    def _unique_rules(self) -> MutationConfig:
        ids = [r.id for r in self.rules]
        twice = sorted({i for i in ids if ids.count(i) > 1})
        if twice:
            raise ValueError(f"rule id(s) given twice: {', '.join(twice)}")
        return self

    def triage(self, mutant: Mutant, originals: dict[str, str] | None = None) -> tuple[str, str] | None:
        """``(reason, by)`` of the first rule (``by``: ``rule:<id>``), else the first entry (``entry``), that
        matches ``mutant``; None when none does. Rules come first."""
        rule = next((r for r in self.rules if r.matches(mutant, originals)), None)
        if rule is not None:
            return rule.reason, f"rule:{rule.id}"
        entry = next((e for e in self.survivors if e.matches(mutant)), None)
        return (entry.reason, "entry") if entry is not None else None


def triage_path(lesson: Lesson) -> Path:
    """``chapters/<lesson>/mutation.yaml``."""
    return lesson.folder / TRIAGE_FILE


def _read_yaml_mapping(path: Path, what: str) -> dict:
    """``path``'s YAML, a mapping ({} when the file is empty).

    Raises:
        LessonFormatError: unreadable YAML, or not a mapping, naming the file.
    """
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise LessonFormatError(f"{path}: not valid YAML: {yaml_error_text(exc)}",
                                "fix the YAML syntax (indentation, quotes)") from exc
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise LessonFormatError(f"{path}: (top level): expected a mapping with {what}, got {type(data).__name__}",
                                "see course/dev/mutants.py for the format")
    return data


def rule_library(chapters: Path) -> dict[str, dict]:
    """The course's shared rules (``chapters/mutation-rules.yaml``, :data:`RULE_LIBRARY`) by id, each as its
    YAML mapping (validated as a :class:`Rule`); {} when the course has none.

    Raises:
        LessonFormatError: unreadable YAML, a rule that is not a valid :class:`Rule`, or an id given twice,
            naming the file.
    """
    path = chapters / RULE_LIBRARY
    if not path.is_file():
        return {}
    data = _read_yaml_mapping(path, "'rules'")
    found: dict[str, dict] = {}
    for index, item in enumerate(data.get("rules") or []):
        try:
            rule = Rule.model_validate(item)
        except ValidationError as exc:
            raise LessonFormatError(format_validation_error(path, exc) + f" (in rules[{index}])",
                                    "a rule has an id, a reason of a sentence and matchers (course/dev/mutants.py: "
                                    "Rule)") from exc
        if rule.id in found:
            raise LessonFormatError(f"{path}: rule id {rule.id} given twice", "give each shared rule one id")
        found[rule.id] = item
    return found


def _expand_uses(path: Path, data: dict, library: Callable[[], dict[str, dict]]) -> dict:
    """``data`` (a ``mutation.yaml``'s mapping) with each ``- use: <id>`` of its ``rules`` replaced by that rule
    of the course's library (``library()``: :func:`rule_library`, read only when a rule is used).

    Raises:
        LessonFormatError: a ``use`` naming no rule of the library, or with other keys beside it.
    """
    rules = data.get("rules")
    if not isinstance(rules, list) or not any(isinstance(r, dict) and "use" in r for r in rules):
        return data
    shared = library()
    expanded = []
    for index, item in enumerate(rules):
        if isinstance(item, dict) and "use" in item:
            if set(item) != {"use"}:
                raise LessonFormatError(f"{path}: rules[{index}]: 'use' takes a shared rule as it is, with no other "
                                        f"key (got {', '.join(sorted(set(item) - {'use'}))})",
                                        "write the rule out in full to change it for this lesson")
            if item["use"] not in shared:
                raise LessonFormatError(f"{path}: rules[{index}]: use: {item['use']!r} is not a rule of "
                                        f"{path.parent.parent / RULE_LIBRARY}",
                                        "shared rules: " + (", ".join(sorted(shared)) or "none"))
            item = shared[item["use"]]
        expanded.append(item)
    return {**data, "rules": expanded}


def load_config(lesson: Lesson) -> MutationConfig:
    """The lesson's ``mutation.yaml`` (an empty config when there is none), its ``- use: <id>`` rules taken from
    the course's library (:func:`rule_library`).

    Raises:
        LessonFormatError: unreadable YAML, a schema violation or a ``use`` of no shared rule, naming the file
            and field.
    """
    path = triage_path(lesson)
    if not path.is_file():
        return MutationConfig()
    data = _read_yaml_mapping(path, "'rules', 'survivors' (and 'files')")
    if not data:
        return MutationConfig()
    data = _expand_uses(path, data, lambda: rule_library(lesson.folder.parent))
    try:
        config = MutationConfig.model_validate(data)
    except ValidationError as exc:
        raise LessonFormatError(format_validation_error(path, exc),
                                "a rule has an id, a reason of a sentence and matchers; a survivor has file, key "
                                "(or line number + original + mutated) and a reason; see course/dev/mutants.py "
                                "(Rule, TriageEntry)") from exc
    if any(rule.starter_line for rule in config.rules):
        starters = {rel: file.read_text(encoding="utf-8", errors="replace").splitlines()
                    for rel, file in _own_starter(lesson).items() if _mutable(file)}
        for rule in config.rules:
            rule._starters = starters
    return config


@dataclasses.dataclass
class Mutant:
    """One mutant: the reference workspace with ``file`` replaced by ``content``.

    Attributes:
        file: the mutated file, workspace-relative (``src/<pkg>/...`` or a lesson folder's file).
        line: the changed line's number in the original, 1-based.
        original: the original line (no newline).
        mutated: the line in the mutant (no newline; "" when the line was deleted).
        content: the mutant file's whole text.
        number: universalmutator's number of the mutant within its file.
        line_index: 0 for the first mutant of the file with these original and mutated lines, 1 for the
            next (the same change of two identical lines), ...: keeps keys unique.
    """

    file: str
    line: int
    original: str
    mutated: str
    content: str
    number: int = 0
    line_index: int = 0

    @property
    def key(self) -> str:
        """Stable id (12 hex digits): hash of the file's path and the original and mutated lines, not of the
        line number, so a mutant keeps its key (and its triage entry) when lines above it change."""
        text = f"{self.file}\0{self.original.strip()}\0{self.mutated.strip()}\0{self.line_index}"
        return hashlib.sha256(text.encode()).hexdigest()[:12]

    @property
    def content_hash(self) -> str:
        """sha256 of the path and the mutant file's text."""
        return hashlib.sha256(f"{self.file}\0{self.content}".encode()).hexdigest()

    def diff(self, original_text: str) -> str:
        """Unified diff of the original file and this mutant (``a/<file>``, ``b/<file>``)."""
        return "".join(difflib.unified_diff(original_text.splitlines(keepends=True),
                                            self.content.splitlines(keepends=True),
                                            f"a/{self.file}", f"b/{self.file}", n=2))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: key, file, line, original line and mutated line (not the whole content)."""
        return {"key": self.key, "file": self.file, "line": self.line, "original": self.original,
                "mutant": self.mutated}


def require_tool(family: str = UNIVERSALMUTATOR) -> None:
    """Raise unless the tool of ``family`` (one of :data:`FAMILIES`) can be imported here.

    Raises:
        MissingRequirement: with the install command as the hint.
        CourseError: ``family`` is not one of :data:`FAMILIES`.
    """
    if family not in FAMILIES:
        raise CourseError(f"unknown mutant family {family!r}", f"one of: {', '.join(FAMILIES)}")
    module = _FAMILY_MODULES[family]
    if importlib.util.find_spec(module) is None:
        raise MissingRequirement(f"dev mutate needs {family}, which is not installed",
                                 f"pip install 'ros2course[mutate]' (or pip install "
                                 f"{_FAMILY_DISTRIBUTIONS.get(family, family)})")


def _own_starter(lesson: Lesson) -> dict[str, Path]:
    folder = getattr(lesson, "starter_dir", None)
    if folder is None or not folder.is_dir():
        return {}
    return {p.relative_to(folder).as_posix(): p for p in folder.rglob("*") if p.is_file()}


def _others_starters(lesson: Lesson) -> set[str]:
    """Paths the starters of the lessons it includes, and every other lesson's own starter, give:
    those lessons teach (and their graders answer for) these files."""
    folders = list(lesson.included_starters)
    try:
        folders += [other.starter_dir for other in load_catalog(lesson.folder.parent.parent).lessons
                    if other.id != lesson.id]
    except CourseError:
        pass  # a lesson outside a catalog: its included starters only
    return {p.relative_to(folder).as_posix() for folder in folders if folder.is_dir()
            for p in folder.rglob("*") if p.is_file()}


def _mutable(path: Path) -> bool:
    if path.suffix.lower() in _SKIP_SUFFIXES or any(part in _SKIP_PARTS or part.endswith(".egg-info")
                                                     for part in path.parts):
        return False
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return False
    return bool(text.strip())


def lesson_files(lesson: Lesson, reference: Path, config: MutationConfig | None = None) -> list[str]:
    """The reference files to mutate, workspace-relative, sorted.

    With ``files`` in ``mutation.yaml``: the files of the reference workspace matching those globs.
    Otherwise the lesson's own work: each text file under the lesson's packages and folders that its
    own starter gives with different content (the learner completes it) or does not give at all (the
    learner writes it), leaving out the files of the lessons it includes (``starter_includes``: their
    graders answer for them) and the finished files its starter hands out (``starter_solutions``, e.g.
    sas-robot-driver's ``sas_lite.py``, "do not change it").

    Args:
        reference: a reference workspace of the lesson (:func:`ros2course.builder.reference.reference_workspace`).
        config: the lesson's ``mutation.yaml`` (None: read it).

    Raises:
        LessonFormatError: ``files`` matches nothing, or mutation.yaml is malformed.
    """
    config = config if config is not None else load_config(lesson)
    every = sorted(p.relative_to(reference).as_posix() for root in lesson.workspace_paths
                   if (reference / root).exists() for p in (reference / root).rglob("*")
                   if p.is_file() and _mutable(p))
    if config.files is not None:
        chosen = [rel for rel in every if any(fnmatch.fnmatch(rel, glob) for glob in config.files)]
        if not chosen:
            raise LessonFormatError(f"{triage_path(lesson)}: files: {config.files} match no file of the reference",
                                    f"name files relative to the workspace, e.g. {every[0] if every else 'src/<pkg>/...'}")
        return chosen
    own, included = _own_starter(lesson), _others_starters(lesson)
    given = tuple(lesson.starter_solutions)
    out = []
    for rel in every:
        if any(rel == folder or rel.startswith(folder + "/") for folder in given):
            continue
        if rel in own:
            if own[rel].read_bytes() != (reference / rel).read_bytes():
                out.append(rel)
        elif rel not in included:
            out.append(rel)
    return out


def _changed_line(original: list[str], mutated: list[str]) -> tuple[int, str, str]:
    """``(1-based line, original line, mutated line)`` of the first difference (regex mutants change one line)."""
    matcher = difflib.SequenceMatcher(a=original, b=mutated, autojunk=False)
    for tag, a0, a1, b0, b1 in matcher.get_opcodes():
        if tag == "equal":
            continue
        old = "".join(original[a0:a1]).rstrip("\n") if a1 > a0 else ""
        new = "".join(mutated[b0:b1]).rstrip("\n") if b1 > b0 else ""
        return a0 + 1, old, new
    return 0, "", ""


#: Files whose ``#`` starts a comment line: shell scripts, CMake, ROS interface definitions, YAML, setup.cfg.
_HASH_COMMENT_SUFFIXES = {".sh", ".bash", ".cmake", ".msg", ".srv", ".action", ".yaml", ".yml", ".cfg", ".toml"}
_HEREDOC = re.compile(r"<<-?\s*['\"]?[A-Za-z_]")


def _xml_shape(text: str) -> Any:
    """An XML document as nested ``(tag, attributes, stripped text, children)``, or None when it does not parse.

    Comments, whitespace and text between elements (``tail``, and the text of an element that has
    children) are not part of it: ROS reads a package.xml's elements and the text of its leaf
    elements (catkin_pkg's parser, REP 149), and Fast DDS an XML profile the same way (its parser,
    on tinyxml2, asks leaf elements for their text).
    """
    def shape(element: ET.Element) -> Any:
        text = (element.text or "").strip() if len(element) == 0 else ""
        return (element.tag, sorted(element.attrib.items()), text, [shape(child) for child in element])
    try:
        return shape(ET.fromstring(text))
    except ET.ParseError:
        return None


def equivalent_mutant(rel: str, original: str, mutated: str, old_line: str, new_line: str) -> bool:
    """Whether a mutant changes nothing a program can see, so it is dropped like universalmutator's own
    equivalents (its Python handler drops mutants with the original's bytecode; its TCE, C++ duplicates).

    Three kinds, for the files universalmutator mutates with its universal rules only: a shell no-op
    proven from the text (:func:`_shell_no_op`), a changed comment line (``#`` comments of shell scripts, CMake, ``.msg``/``.srv``/``.action`` definitions, YAML,
    setup.cfg and TOML such as pyproject.toml; not the ``#!`` line, and never in a script with a here-document, where ``#`` lines are
    data), and an XML file (package.xml, launch XML) whose mutant parses to the same elements,
    attributes and texts (:func:`_xml_shape`). A mutant that breaks the XML is invalid (:func:`invalid_mutant`).

    Args:
        rel: the file's path in the reference (its suffix and name pick the rule).
        original, mutated: the whole file before and after.
        old_line, new_line: the changed line before and after (:func:`_changed_line`).
    """
    name = Path(rel).name
    suffix = Path(rel).suffix.lower()
    if suffix == ".xml":
        before = _xml_shape(original)
        return before is not None and _xml_shape(mutated) == before
    if suffix in _HASH_COMMENT_SUFFIXES or name == "CMakeLists.txt":
        if suffix in {".sh", ".bash"} and _HEREDOC.search(original):
            return False
        old, new = old_line.lstrip(), new_line.lstrip()
        if (old.startswith("#") and new.startswith("#") and not old.startswith("#!")
                and "\n" not in old_line and "\n" not in new_line):
            return True
        return suffix in {".sh", ".bash"} and _shell_no_op(original, mutated, old_line, new_line)
    return False


#: ``for NAME in WORDS; do`` on one line (the loops the course's scripts write).
_SHELL_FOR = re.compile(r"^(\s*)for\s+([A-Za-z_]\w*)\s+in\s+(.*?)\s*;\s*do\s*$")
#: A word bash takes as it is: no expansion, quoting, globbing or arithmetic.
_SHELL_LITERAL = re.compile(r"^[A-Za-z0-9_.,:+=@%-]+$")


def _shell_no_op(original: str, mutated: str, old_line: str, new_line: str) -> bool:
    """Two shell mutants that change nothing bash does, proven from the text (never a judgement):

    * a value of a ``for NAME in WORDS; do`` list replaced by another plain word, when the loop's body
      never names ``NAME``: the loop runs as many times with the same body (the discovery loops'
      ``for attempt in 1 2 ... 10``, whose counter only counts);
    * ``continue`` inserted as the last command of a loop's body, right before its ``done``.

    A script that uses ``eval`` or indirect expansion (``${!``) is never judged (a name may hide there).
    """
    if "eval" in original.split() or "${!" in original:
        return False
    before = _SHELL_FOR.match(old_line.rstrip("\n"))
    after = _SHELL_FOR.match(new_line.rstrip("\n"))
    if before and after:
        if before.group(1, 2) != after.group(1, 2):
            return False
        old_words, new_words = before.group(3).split(), after.group(3).split()
        if len(old_words) != len(new_words) or not all(_SHELL_LITERAL.match(w) for w in old_words + new_words):
            return False
        lines = original.splitlines()
        start = next((i for i, text in enumerate(lines) if text == old_line.rstrip("\n")), None)
        if start is None:
            return False
        depth, body = 0, []
        for index in range(start, len(lines)):
            for word in _shell_do_done(lines[index]):
                depth += 1 if word == "do" else -1
            if index > start:
                body.append(_shell_code(lines[index]))
            if depth == 0:
                break
        if depth != 0:
            return False
        return not re.search(rf"(?<![\w]){re.escape(before.group(2))}(?!\w)", "\n".join(body))
    if old_line.strip() or not re.fullmatch(r"\s*continue\s*;?\s*", new_line.rstrip("\n")):
        return False
    # an inserted `continue`: the next command after it closes its loop
    mutated_lines = mutated.splitlines()
    inserted = [i for i, text in enumerate(mutated_lines) if text == new_line.rstrip("\n")]
    for index in inserted:
        following = next((_shell_code(t).strip() for t in mutated_lines[index + 1:] if _shell_code(t).strip()), "")
        if following in ("done", "done;") and _shell_loops_open(mutated_lines[:index]):
            return True
    return False


def invalid_mutant(rel: str, mutated: str) -> bool:
    """Whether a mutant is not a program at all, so it is dropped as universalmutator's Python handler
    drops a ``.py`` mutant that does not compile: an XML file (package.xml, launch XML) that no longer
    parses. colcon (catkin_pkg) rejects such a package.xml before any check runs, so it would only be
    "killed by build", telling nothing of the grader, and package.xml's character-level mutants are
    mostly such (simplest-python-package: 25 of a 30-mutant sample), crowding a sample out.

    Args:
        rel: the file's path in the reference (its suffix picks the rule).
        mutated: the whole mutated file.
    """
    return Path(rel).suffix.lower() == ".xml" and _xml_shape(mutated) is None


def generate_file_mutants(reference: Path, rel: str) -> list[Mutant]:
    """Every mutant universalmutator makes of ``reference/rel``, in its order.

    Python files are checked by universalmutator's Python handler (mutants that do not compile, or
    compile to the original's bytecode, are dropped); other files are not checked (``--noCheck``),
    but an XML mutant that does not parse is dropped as invalid (:func:`invalid_mutant`), and a
    mutant of a comment line or an XML mutant with the same elements as equivalent
    (:func:`equivalent_mutant`).

    Raises:
        MissingRequirement: universalmutator is not installed.
        CourseError: universalmutator failed on the file (its output's last line in the message).
    """
    require_tool()
    source = reference / rel
    original = source.read_text(encoding="utf-8")
    language = LANGUAGES.get(source.suffix.lower())
    with tempfile.TemporaryDirectory(prefix="ros2course-mutants-") as tmp:
        work = Path(tmp)
        copy = work / source.name
        shutil.copyfile(source, copy)
        script = "import sys; from universalmutator.genmutants import main; sys.argv[0] = 'mutate'; main()"
        argv = [sys.executable, "-c", script, copy.name]
        if language:
            argv.append(language)
        argv += ["--mutantDir", "mutants"]
        if language not in CHECKED_LANGUAGES:
            argv.append("--noCheck")
        run = subprocess.run(argv, cwd=work, capture_output=True, text=True, timeout=600, check=False)
        folder = work / "mutants"
        if run.returncode != 0 or not folder.is_dir():
            last = (run.stderr or run.stdout).strip().splitlines()[-1:] or ["no output"]
            raise CourseError(f"universalmutator failed on {rel} (exit code {run.returncode}): {last[0]}",
                              "run `mutate FILE --mutantDir DIR` on that file to see why")
        stem, suffix = copy.stem, copy.suffix
        found = []
        for path in folder.iterdir():
            middle = path.name[len(stem) + len(".mutant."):len(path.name) - len(suffix)] if suffix else \
                path.name[len(stem) + len(".mutant."):]
            if path.name.startswith(f"{stem}.mutant.") and middle.isdigit():
                found.append((int(middle), path.read_text(encoding="utf-8", errors="replace")))
    lines = original.splitlines(keepends=True)
    out: list[Mutant] = []
    seen: dict[tuple[str, str], int] = {}
    for number, content in sorted(found):
        if content != original and not invalid_mutant(rel, content):
            if (mutant := _keyed_mutant(rel, original, lines, content, number, seen)) is not None:
                out.append(mutant)
    return out


def _keyed_mutant(rel: str, original: str, lines: list[str], content: str, number: int,
                  seen: dict[tuple[str, str], int]) -> Mutant | None:
    """The :class:`Mutant` that ``content`` (a whole mutated file) is of ``original`` (``lines``: its lines, ends
    kept), or None when :func:`equivalent_mutant` says it changes nothing; the one keying step of both families'
    generators, so an edit both tools make gets the same :attr:`Mutant.key`.

    ``seen`` counts the file's mutants per (original line, mutated line), both stripped: the count so far is the
    new mutant's ``line_index``, and it is updated here.
    """
    line, old, new = _changed_line(lines, content.splitlines(keepends=True))
    if equivalent_mutant(rel, original, content, old, new):
        return None
    index = seen.get((old.strip(), new.strip()), 0)
    seen[(old.strip(), new.strip())] = index + 1
    return Mutant(rel, line, old, new, content, number, index)


def generate_mutants(lesson: Lesson, reference: Path, config: MutationConfig | None = None,
                     family: str = UNIVERSALMUTATOR) -> list[Mutant]:
    """The mutants of every file of :func:`lesson_files`, file by file, made by ``family``'s tool
    (:data:`FAMILIES`; cosmic-ray, mutmut and poodle mutate only the ``.py`` files among them).

    Raises:
        MissingRequirement: the family's tool is not installed.
        LessonFormatError: a malformed ``mutation.yaml``.
        CourseError: the lesson has no file to mutate, or universalmutator failed.
    """
    files = lesson_files(lesson, reference, config)
    if not files:
        raise CourseError(f"lesson {lesson.id} has no reference file to mutate",
                          f"name them with 'files:' in {triage_path(lesson)}")
    python_only = {COSMIC_RAY: generate_cosmic_ray_mutants, MUTMUT: generate_mutmut_mutants,
                   POODLE: generate_poodle_mutants, MUTPY: generate_mutpy_mutants}.get(family)
    if python_only is not None:
        return [m for rel in files if rel.endswith(".py") for m in python_only(reference, rel)]
    return [m for rel in files for m in generate_file_mutants(reference, rel)]


def _bytecode(text: str, rel: str) -> bytes | None:
    """The marshalled code object of Python source ``text`` (None when it does not compile)."""
    try:
        with warnings.catch_warnings():  # an `is` with a literal (a comparison operator's mutant) warns
            warnings.simplefilter("ignore", SyntaxWarning)
            return marshal.dumps(compile(text, rel, "exec", dont_inherit=True))
    except (SyntaxError, ValueError):
        return None


def _compiled_mutants(rel: str, original: str, contents: Iterable[str]) -> list[Mutant]:
    """The mutants of the Python file ``rel`` (source ``original``) among ``contents`` (whole mutated files, in
    the tool's order), numbered from 1 in that order. Dropped, as universalmutator's trivial-compiler-equivalence
    check drops them: a content made before (or the original), one that does not compile, one that compiles
    to the original's bytecode, and one :func:`_keyed_mutant` finds equivalent; the step the cosmic-ray and
    mutmut generators share."""
    base = _bytecode(original, rel)
    lines = original.splitlines(keepends=True)
    out: list[Mutant] = []
    made: set[str] = {original}
    seen: dict[tuple[str, str], int] = {}
    for content in contents:
        if content in made:
            continue
        made.add(content)
        code = _bytecode(content, rel)
        if code is None or code == base:
            continue
        if (mutant := _keyed_mutant(rel, original, lines, content, len(out) + 1, seen)) is not None:
            out.append(mutant)
    return out


def generate_cosmic_ray_mutants(reference: Path, rel: str) -> list[Mutant]:
    """Every mutant cosmic-ray's core operators make of the Python file ``reference/rel``, in a fixed order
    (operators by name, then each operator's occurrences in the file).

    Each mutant is one operator applied at one place (``cosmic_ray.mutating.mutate_code``), as cosmic-ray
    applies them. Dropped, as for universalmutator's Python mutants (its trivial-compiler-equivalence
    check): a mutant that does not compile, that compiles to the original's bytecode, or that another
    operator already made; the operators that need a user's variable names (``core/VariableInserter``,
    ``core/VariableReplacer``) are not used. A mutant universalmutator also makes has the same
    :attr:`Mutant.key` (the key is the path and the edit), so a sample never draws an edit twice.

    Raises:
        MissingRequirement: cosmic-ray is not installed.
    """
    require_tool(COSMIC_RAY)
    from cosmic_ray import plugins  # noqa: PLC0415 - optional: the mutate extra
    from cosmic_ray.mutating import mutate_code  # noqa: PLC0415 - optional: the mutate extra

    original = (reference / rel).read_text(encoding="utf-8")

    def edits() -> Iterator[str]:
        for name in sorted(plugins.operator_names()):
            try:
                operator = plugins.get_operator(name)()
            except TypeError:  # needs arguments: the variable names to insert or replace
                continue
            occurrence = 0
            while (content := mutate_code(original, operator, occurrence)) is not None:
                occurrence += 1
                yield content

    return _compiled_mutants(rel, original, edits())


def generate_mutmut_mutants(reference: Path, rel: str) -> list[Mutant]:
    """Every mutant mutmut 2 makes of the Python file ``reference/rel``, in mutmut's own order (its
    ``list_mutations``: the file's nodes in order, each node's mutations by index), one edit each
    (``mutmut.mutate`` with that mutation id), as ``mutmut run`` applies them.

    mutmut 2, not 3: mutmut 3 writes one "trampolined" file holding every mutant of a function as a function
    of its own, switched at run time, so it has no one-edit file to grade; mutmut 2's ``Context`` /
    ``list_mutations`` / ``mutate`` is the single-edit API. Dropped, as for the other families: a mutant that
    does not compile, that compiles to the original's bytecode, or that an earlier mutation already made
    (:func:`_keyed_mutant`: an edit another tool also makes gets the same :attr:`Mutant.key`, so a held-out
    draw never takes it twice).

    Raises:
        MissingRequirement: mutmut is not installed.
    """
    require_tool(MUTMUT)
    from mutmut import Context, list_mutations, mutate  # noqa: PLC0415 - optional: the mutate extra

    original = (reference / rel).read_text(encoding="utf-8")
    edits = (mutate(Context(source=original, mutation_id=mutation_id, filename=rel, dict_synonyms=[]))[0]
             for mutation_id in list_mutations(Context(source=original, filename=rel, dict_synonyms=[])))
    return _compiled_mutants(rel, original, edits)


def generate_poodle_mutants(reference: Path, rel: str) -> list[Mutant]:
    """Every mutant poodle's built-in mutators make of the Python file ``reference/rel``, in poodle's own order
    (its ``builtin_mutators``, each mutator's mutations in the order it visits the syntax tree), one edit each,
    applied as poodle applies them (``poodle.util.mutate_lines``: the node's source span replaced by the
    mutator's text).

    The fourth family (issue 37), for lessons whose universalmutator, cosmic-ray and mutmut pools are all spent:
    a fourth tool (Python ``ast`` visitors) with operators none of the three has: a call replaced by ``None``,
    a subscript replaced by ``None``, a ``return`` of ``None``, a decorator removed, ``None`` replaced by
    ``' '``, an augmented assignment made plain. Every built-in mutator is used with poodle's default options
    (``mutator_opts`` empty: operator level ``std``; its one default filter leaves ``__name__ == '__main__'``
    alone). Dropped, as for the other families (:func:`_compiled_mutants`): a mutant that does not compile,
    that compiles to the original's bytecode, or that an earlier mutation already made; an edit another tool
    also makes has the same :attr:`Mutant.key`, so a held-out draw never takes it twice.

    Raises:
        MissingRequirement: poodle is not installed.
    """
    require_tool(POODLE)
    from poodle.mutate import builtin_mutators  # noqa: PLC0415 - optional: the mutate extra
    from poodle.util import mutate_lines  # noqa: PLC0415 - optional: the mutate extra

    original = (reference / rel).read_text(encoding="utf-8")
    lines = original.splitlines(keepends=True)
    tree = ast.parse(original, rel)
    # poodle's mutators read one thing of its PoodleConfig, ``mutator_opts``; building a whole PoodleConfig
    # (poodle.config.build_config) would read a poodle.toml or pyproject.toml from the working directory.
    options = types.SimpleNamespace(mutator_opts={})

    def edits() -> Iterator[str]:
        for mutator_class in builtin_mutators.values():
            mutator = mutator_class(config=options, echo=lambda *_, **__: None)
            for mutation in mutator.create_mutations(parsed_ast=copy.deepcopy(tree), file_lines=list(lines)):
                yield "".join(mutate_lines(mutation, lines))

    return _compiled_mutants(rel, original, edits())


def generate_mutpy_mutants(reference: Path, rel: str) -> list[Mutant]:
    """Every mutant MutPy's operators make of the Python file ``reference/rel`` (mutpy-pynguin, the maintained
    fork of MutPy): its 20 standard operators and 7 experimental ones, by name, each operator's mutations in
    the order it visits the syntax tree.

    The fifth family (issue 37), for lessons whose four other pools are spent: operators none of the four has
    as such, on the object model a ROS node is written in: ``self.x`` made ``x`` (SVD), an exception handler's
    body swallowed or re-raised (EXS, EHD), a ``super()`` call removed or moved (SCD, SCI), a loop run zero
    times, once or reversed (ZIL, OIL, RIL), a statement replaced by ``pass`` (SDL), a decorator removed or a
    ``classmethod`` / ``staticmethod`` one added (DDL, CDI, SDI), a hiding variable removed (IHD), an
    overriding method removed (IOD), a slice's index removed (SIR), constants replaced (CRP).

    MutPy mutates a syntax tree and writes the whole module back with its own code generator, which would
    reformat every line; here each mutation is spliced into the original text instead: the source span of
    the smallest mutated node that has one (a decorated definition's span starts at its first decorator) is
    replaced by ``ast.unparse`` of what the tree holds there now, its later lines indented as the span's
    first line. So the rest of the file keeps its text, but the spliced span is in ``ast.unparse``'s style
    (single quotes, no redundant parentheses): an edit another family also makes may then differ from it in
    text only, and its :attr:`Mutant.key` with it, which is why :func:`drop_made_by_others` removes the
    mutants whose syntax tree another family's mutant already has. Dropped as for the other families
    (:func:`_compiled_mutants`). An operator that raises on this file (MutPy predates Python 3.11's syntax
    tree in places) gives the mutants it made before it raised.

    Raises:
        MissingRequirement: mutpy-pynguin is not installed.
    """
    require_tool(MUTPY)
    import mutpy.operators as mutpy_operators  # noqa: PLC0415 - optional: the mutate extra
    from mutpy import utils as mutpy_utils  # noqa: PLC0415 - optional: the mutate extra

    original = (reference / rel).read_text(encoding="utf-8")
    lines = original.splitlines(keepends=True)
    operators = sorted([*mutpy_operators.standard_operators, *mutpy_operators.experimental_operators],
                       key=lambda cls: cls.name())

    def edits() -> Iterator[str]:
        for mutpy_operator in operators:
            tree = mutpy_utils.create_ast(original)
            slots = _slots(tree)
            with warnings.catch_warnings():  # MutPy reads ast.Str / ast.Num, deprecated in Python 3.8+
                warnings.simplefilter("ignore", DeprecationWarning)
                try:
                    for mutation, _ in mutpy_operator().mutate(tree):
                        content = _splice_mutation(lines, mutation.node, slots)
                        if content is not None:
                            yield content
                except Exception:  # noqa: BLE001, S112 - MutPy's operator failed on this file: its other mutants are kept
                    continue
                finally:
                    _unmark_shared_nodes(tree)

    return _compiled_mutants(rel, original, edits())


def _unmark_shared_nodes(tree: ast.AST) -> None:
    """Remove what MutPy wrote on the nodes CPython's parser shares between every tree it makes (``Load``,
    ``Store``, the operators: one instance each, with no position of their own): a ``lineno`` there made the
    next tool that reads positions (cosmic-ray, poodle, ``ast`` itself) fail on every later file."""
    for node in ast.walk(tree):
        if not type(node)._attributes:
            for name in ("lineno", "parent", "children", "marker"):
                node.__dict__.pop(name, None)


def _slots(tree: ast.AST) -> dict[int, tuple[ast.AST, str, int | None, int]]:
    """Where each node of ``tree`` sits: ``id(node) -> (parent, field, index in the field's list or None,
    the list's length then)``."""
    out: dict[int, tuple[ast.AST, str, int | None, int]] = {}
    for parent in ast.walk(tree):
        for field, value in ast.iter_fields(parent):
            if isinstance(value, list):
                for index, item in enumerate(value):
                    if isinstance(item, ast.AST):
                        out[id(item)] = (parent, field, index, len(value))
            elif isinstance(value, ast.AST):
                out[id(value)] = (parent, field, None, 0)
    return out


def _span(node: ast.AST) -> tuple[int, int, int, int] | None:
    """``(first line, first column, last line, end column)`` of ``node`` in its source (1-based lines, UTF-8
    byte columns as ``ast`` gives them), from its first decorator when it has some; None without positions."""
    try:
        span = [node.lineno, node.col_offset, node.end_lineno, node.end_col_offset]  # type: ignore[attr-defined]
    except AttributeError:
        return None
    if None in span:
        return None
    for decorator in getattr(node, "decorator_list", None) or []:
        if hasattr(decorator, "lineno") and (decorator.lineno, decorator.col_offset - 1) < (span[0], span[1]):
            span[0], span[1] = decorator.lineno, decorator.col_offset - 1
    return span[0], span[1], span[2], span[3]


def _splice_mutation(lines: list[str], node: ast.AST, slots: dict[int, tuple[ast.AST, str, int | None, int]]
                     ) -> str | None:
    """The whole file ``lines`` with the mutation MutPy made at ``node`` spliced in (see
    :func:`generate_mutpy_mutants`), or None when it cannot be placed."""
    target = node
    while _span(target) is None:  # an operator (ast.Add) or a context has no span: its nearest ancestor's
        if id(target) not in slots:
            return None
        target = slots[id(target)][0]
    if id(target) not in slots:
        return None
    parent, field, index, length = slots[id(target)]
    now = getattr(parent, field, None)
    if target is not node:  # the ancestor itself stays in its slot, changed below
        replacement: list[ast.AST] = [target]
    elif index is None:
        replacement = [] if now is None else [now]
    else:  # a list: the slot's one item may now be several, or none
        count = len(now) - length + 1
        replacement = list(now[index:index + count]) if count > 0 else []
    try:
        text = "\n".join(ast.unparse(item) for item in replacement)
    except Exception:  # noqa: BLE001 - a tree MutPy left that ast cannot write back
        return None
    first, col, last, end = _span(target)  # type: ignore[misc]
    head = lines[first - 1].encode()[:col].decode(errors="replace")
    tail = lines[last - 1].encode()[end:].decode(errors="replace")
    if not text and isinstance(target, ast.stmt):
        text = "pass"
    indent = " " * len(head) if not head.strip() else ""
    text = text.replace("\n", "\n" + indent)
    return "".join(lines[:first - 1]) + head + text + tail + "".join(lines[last:])


def drop_made_by_others(mutants: list[Mutant], others: Iterable[Mutant]) -> list[Mutant]:
    """``mutants`` without those whose file's syntax tree one of ``others`` (another family's mutants of the same
    files) already has: the same edit written in another style (:func:`generate_mutpy_mutants`). A file that
    does not parse as Python is compared by its text."""
    def form(mutant: Mutant) -> tuple[str, str]:
        if mutant.file.endswith(".py"):
            with contextlib.suppress(SyntaxError, ValueError), warnings.catch_warnings():
                warnings.simplefilter("ignore", SyntaxWarning)
                return mutant.file, ast.dump(ast.parse(mutant.content))
        return mutant.file, mutant.content

    made = {form(m) for m in others}
    return [m for m in mutants if form(m) not in made]


def sample_mutants(mutants: list[Mutant], count: int | None, seed: int) -> list[Mutant]:
    """``count`` mutants picked with ``random.Random(seed)`` (all when ``count`` is None or not smaller).

    Raises:
        CourseError: ``count`` below 1.
    """
    if count is None or count >= len(mutants):
        return list(mutants)
    if count < 1:
        raise CourseError(f"--sample must be at least 1 (got {count})", "e.g. --sample 30")
    picked = set(random.Random(seed).sample(range(len(mutants)), count))
    return [m for i, m in enumerate(mutants) if i in picked]


def held_out_sample(candidates: list[Mutant], first: list[Mutant], count: int, seed: int,
                    recorded: set[str] | frozenset[str] = frozenset()) -> list[Mutant]:
    """The held-out sample: ``count`` mutants picked with ``random.Random(seed)`` (:func:`sample_mutants`, the
    first sample's scheme with another seed) from ``candidates`` minus the first sample (``first``, and the
    keys of ``recorded``: the first sample as its run recorded it), so the two are disjoint; every one left
    when fewer than ``count`` are.

    Raises:
        CourseError: ``count`` below 1.
    """
    if count < 1:
        raise CourseError(f"--held-out must be at least 1 (got {count})", "e.g. --held-out 30")
    taken = {m.key for m in first} | set(recorded)
    return sample_mutants([m for m in candidates if m.key not in taken], count, seed)


def unjudged(result: LessonResult) -> set[str]:
    """Ids of the checks a grading stopped early (:class:`~ros2course.grade.checklist.StopWhen`: ``dev validate
    --until-settled``, ``dev mutate --first-loss``) left unjudged ("not checked: " +
    :data:`~ros2course.grade.checklist.STOPPED_SETTLED`); empty for a whole grading."""
    return {c.id for c in result.checks if c.skipped and c.observed == NOT_CHECKED + STOPPED_SETTLED}


def classify(result: LessonResult) -> tuple[str, list[str]]:
    """``(outcome, lost checks)`` of a mutant's grading (see the module docstring for the outcomes)."""
    if result.status == Status.GRADER_ERROR:
        return GRADER_ERROR, []
    if result.status == Status.NOT_GRADABLE:
        message = result.message or ""
        if message.startswith("timed out"):
            return TIMED_OUT, []
        # the build failed, or colcon could not even read the package (a broken package.xml): the
        # checks never ran, so it says nothing about the grader
        return KILLED_BY_BUILD, ["build"]
    cut = unjudged(result)  # a check left "not checked" by a stop at the first loss was never judged
    lost = [c.id for c in result.checks if c.points < c.max_points and c.id not in cut]
    if "build" in lost:
        return KILLED_BY_BUILD, lost
    if result.score >= result.max_score and not lost:
        return SURVIVED, []
    return KILLED, lost


def _hash_files(paths: list[Path], root: Path) -> str:
    digest = hashlib.sha256()
    for path in sorted(paths):
        if path.is_file() and "__pycache__" not in path.parts:
            digest.update(f"{path.relative_to(root)}\0".encode() + path.read_bytes() + b"\0")
    return digest.hexdigest()


def grader_hash(lesson: Lesson) -> str:
    """sha256 (hex) over the paths and contents of every file the lesson's grader fingerprint covers
    (:func:`ros2course.grade.fingerprint.grader_files`: the grader and its helper modules and data, the engine
    modules they import, ``lesson.yaml``, the reference): the mutant cache's key of the grader.

    One list for both, so a cached outcome is reused exactly when the fingerprint is the same: stop 66 found a
    hand-made list here narrower than the fingerprint (``grade/machine.py`` was not in it), and outcomes graded
    before a fix to that file were reused after it.
    """
    from ros2course.grade.fingerprint import grader_files  # noqa: PLC0415 - reads the course's files

    root = lesson.course.root
    paths = grader_files(lesson)
    return _hash_files(paths, root if all(p.is_relative_to(root) for p in paths) else Path("/"))


def course_hash(reference: Path, lesson: Lesson) -> str:
    """sha256 of the reference workspace a mutant starts from and of the lesson's ``lesson.yaml``."""
    digest = hashlib.sha256(_hash_files([p for p in reference.rglob("*")], reference).encode())
    digest.update((lesson.folder / "lesson.yaml").read_bytes())
    return digest.hexdigest()


def cache_key(grader: str, course: str, mutant: Mutant) -> str:
    """The cache's key of a mutant's outcome: (grader source, course content, mutant content)."""
    return hashlib.sha256(f"{grader}\0{course}\0{mutant.content_hash}".encode()).hexdigest()[:32]


@dataclasses.dataclass
class Graded:
    """A mutant and how its grading ended."""

    mutant: Mutant
    outcome: str
    lost: list[str]
    score: float = 0.0
    max_score: float = 0.0
    message: str = ""
    cached: bool = False
    triaged: str = ""  #: the triage reason when ``mutation.yaml`` covers this survivor
    triaged_by: str = ""  #: ``rule:<id>`` or ``entry``, with ``triaged``
    rule: str = ""  #: the id of the rule matching it, whatever its outcome (a killed mutant a rule matches)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the mutant's fields, outcome, lost checks, score, message, cached, triage reason."""
        return {**self.mutant.to_dict(), "outcome": self.outcome, "lost": self.lost, "score": self.score,
                "max_score": self.max_score, "message": self.message, "cached": self.cached,
                "triaged": self.triaged, "triaged_by": self.triaged_by}


def set_aside(mutants: list[Mutant], config: MutationConfig) -> tuple[list[Mutant], list[Mutant]]:
    """``(to grade, set aside)``: the mutants of the rules marked ``set_aside`` are set aside before sampling.
    Whatever they change, the author judged it outside the contract (a script's ``#!`` line the checker
    never reads, a package.xml description), so grading them would only spend the sample (inspect-topics:
    18 of its first 30 were such)."""
    whole = [r for r in config.rules if r.set_aside]
    aside = [m for m in mutants if any(r.matches(m) for r in whole)]
    keys = {m.key for m in aside}
    return [m for m in mutants if m.key not in keys], aside


def apply_triage(graded: list[Graded], config: MutationConfig, every: list[Mutant],
                 originals: dict[str, str] | None = None) -> list[TriageEntry | Rule]:
    """Mark triaged survivors (``Graded.triaged``, rules first, then entries) and the rule matching each
    graded mutant (``Graded.rule``: a rule matching a killed mutant is shown); return the *stale* entries
    and rules (matching no current mutant; none when ``every`` is empty: nothing to judge by).

    Args:
        graded: the graded mutants (only survivors get triaged).
        config: the lesson's ``mutation.yaml``.
        every: every mutant generated now (not only the sample): an entry is stale only when it matches none.
        originals: ``{file: original text}`` for mutants known only by their record (no content).
    """
    for item in graded:
        item.triaged = item.triaged_by = item.rule = ""
        rule = next((r for r in config.rules if r.matches(item.mutant, originals)), None)
        item.rule = rule.id if rule is not None else ""
        if item.outcome == SURVIVED:
            found = config.triage(item.mutant, originals)
            if found is not None:
                item.triaged, item.triaged_by = found
    if not every:
        return []
    return [*(r for r in config.rules if not any(r.matches(m) for m in every)),
            *(e for e in config.survivors if not any(e.matches(m) for m in every))]


@dataclasses.dataclass
class LessonMutation:
    """What ``dev mutate`` found for one lesson.

    Attributes:
        generated: mutants universalmutator made of the lesson's files.
        graded: the graded ones (all, or the ``--sample``), with outcomes.
        stale: ``mutation.yaml`` entries and rules matching no generated mutant.
        sampled: True when ``graded`` is a sample.
        seconds: wall time of the lesson (generation, grading, classification), seconds.
        set_aside: generated mutants of the rules marked ``set_aside``: never sampled nor graded
            (:func:`set_aside`), so a sample is spent on mutants that count.
        sample, seed: the sample's size asked for (None: all) and its seed.
        held_out: this is a held-out sample (:func:`held_out_sample`), not the first (tuned) one.
        pool: the mutants the sample was drawn from (the first sample's left out for a held-out one).
        family: the tool that made the sample's mutants (:data:`FAMILIES`).
    """

    lesson: str
    generated: int
    graded: list[Graded]
    stale: list[TriageEntry | Rule]
    sampled: bool
    seconds: float = 0.0
    diffs: dict[str, str] = dataclasses.field(default_factory=dict)  #: survivor key -> unified diff
    set_aside: int = 0
    sample: int | None = None
    seed: int = 1
    held_out: bool = False
    pool: int = 0
    family: str = UNIVERSALMUTATOR

    def count(self, outcome: str) -> int:
        """How many graded mutants ended with ``outcome`` (one of :data:`OUTCOMES`)."""
        return sum(g.outcome == outcome for g in self.graded)

    @property
    def triaged(self) -> int:
        """How many survivors ``mutation.yaml`` triages."""
        return sum(bool(g.triaged) for g in self.graded)

    @property
    def score(self) -> float | None:
        """killed / (graded - killed by build - triaged), or None when nothing counts."""
        denominator = len(self.graded) - self.count(KILLED_BY_BUILD) - self.triaged
        return self.count(KILLED) / denominator if denominator > 0 else None

    @property
    def by_rule(self) -> int:
        """How many survivors a rule triages (the rest of :attr:`triaged`, entries)."""
        return sum(g.triaged_by.startswith("rule:") for g in self.graded)

    @property
    def raw(self) -> float | None:
        """killed / (graded - killed by build), before any triage, or None when nothing was judged."""
        judged = len(self.graded) - self.count(KILLED_BY_BUILD)
        return self.count(KILLED) / judged if judged > 0 else None

    def uncovered(self) -> list[str]:
        """The survivors no rule nor entry covers, as ``file:line (key)``, sorted."""
        return sorted(f"{g.mutant.file}:{g.mutant.line} ({g.mutant.key})" for g in self.graded
                      if g.outcome == SURVIVED and not g.triaged)

    def rules_on_killed(self) -> list[str]:
        """Graded mutants a rule matches that the grader killed (``rule: file:line (key)``): evidence that the
        kind is not equivalent after all, for the author to look at."""
        return sorted(f"{g.rule}: {g.mutant.file}:{g.mutant.line} ({g.mutant.key})" for g in self.graded
                      if g.rule and g.outcome == KILLED)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (counts, score, stale entries) and every graded mutant (``mutation.json``)."""
        return {"lesson": self.lesson, "generated": self.generated, "graded": len(self.graded),
                "sampled": self.sampled, "killed": self.count(KILLED), "killed_by_build": self.count(KILLED_BY_BUILD),
                "survived": self.count(SURVIVED), "triaged": self.triaged, "triaged_by_rule": self.by_rule,
                "timed_out": self.count(TIMED_OUT),
                "grader_error": self.count(GRADER_ERROR), "score": self.score, "raw": self.raw,
                "seconds": round(self.seconds, 1), "set_aside": self.set_aside, "sample": self.sample,
                "seed": self.seed, "held_out": self.held_out, "pool": self.pool, "family": self.family,
                "rules_on_killed": self.rules_on_killed(),
                "stale": [e.model_dump(exclude_none=True) for e in self.stale],
                "mutants": [g.to_dict() for g in self.graded]}


def course_version() -> str:
    """The current course's version (``course.yaml``), "" for a course without a manifest."""
    root = content_root()
    return load_manifest(root).version if (root / MANIFEST).is_file() else ""


def _outcome_rows(found: LessonMutation) -> list[dict[str, Any]]:
    return [{"key": g.mutant.key, "file": g.mutant.file, "line": g.mutant.line,
             "original": g.mutant.original.strip(), "mutant": g.mutant.mutated.strip(),
             "outcome": g.outcome, "lost": g.lost, **({"triaged": g.triaged, "triaged_by": g.triaged_by}
                                                      if g.triaged else {}),
             **({"rule": g.rule} if g.rule and not g.triaged else {})}
            for g in sorted(found.graded, key=lambda g: (g.mutant.file, g.mutant.line, g.mutant.key))]


def _summary(found: LessonMutation) -> dict[str, Any]:
    return {key: value for key, value in found.to_dict().items()
            if key not in ("mutants", "stale", "lesson", "held_out", "raw")}


def read_json_object(path: Path) -> dict[str, Any]:
    """The JSON object in ``path``; {} when the file is missing, unreadable, not JSON or not an object
    (a record or cache that is not there yet reads as empty)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def write_score(lesson: Lesson, found: LessonMutation, measured: dict[str, str] | None = None,
                keep_held_out: bool = False) -> Path | None:
    """Record ``found``'s counts and score in ``chapters/<lesson>/mutation-score.json``; its path, or None.

    The file lives with the lesson, like its ``mutation.yaml``, so that ``dev validate``
    (:func:`describe_score`) and whoever reads the course see the grader's last
    measured strength; commit it with the lesson. Every mutant's outcome goes to
    ``mutation-outcomes.json`` beside it. ``measured`` (``date``, ``fingerprint``, optionally
    ``course_version``) names the run the outcomes come from when it is not now (a re-triage of an
    old run keeps its date, its grader fingerprint and the course version it was graded under).
    None when the lesson folder is read-only (an installed course): the run's ``mutation.json``
    still has it all.

    A held-out run (``found.held_out``) goes to the ``held_out`` section of both files, beside the
    first sample's figures (:func:`write_held_out`). A new first sample drops the recorded held-out
    one (it must be drawn after the first, from what the first left); ``keep_held_out`` keeps it (a
    re-triage of the first sample: the held-out one stays as it was graded, never re-triaged).
    """
    if found.held_out:
        return write_held_out(lesson, found, measured)
    from ros2course.grade.fingerprint import measurement  # noqa: PLC0415 - reads the course's files

    measured = measured or measurement(lesson)
    fingerprint = measured["fingerprint"]
    data = _summary(found)
    data.update(date=measured["date"], course_version=measured.get("course_version") or course_version(),
                fingerprint=fingerprint,
                **course_part(measured), survivors=found.uncovered())
    # every mutant's outcome, committed with the lesson: the figure can be checked and re-derived (issue 37)
    outcomes = {"fingerprint": fingerprint, "date": data["date"], "mutants": _outcome_rows(found)}
    if keep_held_out:
        # the held-out section, and what earlier held-out samples showed and scored, stay as they were recorded
        before_score = read_json_object(lesson.folder / SCORE_FILE)
        before_outcomes = read_json_object(lesson.folder / OUTCOMES_FILE)
        for key in ("held_out", EARLIER_KEY):
            if key in before_score:
                data[key] = before_score[key]
        for key in ("held_out", SHOWN_KEY):
            if key in before_outcomes:
                outcomes[key] = before_outcomes[key]
    else:
        if shown := recorded_held_out(lesson):
            # the held-out figures go with the old first sample, but what its samples showed stays shown: a mutant
            # whose survival the author has seen is tuned, and no later held-out sample may draw it again
            outcomes[SHOWN_KEY] = sorted(shown)
        if history := held_out_history(read_json_object(lesson.folder / SCORE_FILE)):
            data[EARLIER_KEY] = history  # and what they scored stays on record (shown beside the next one)
    return _write_records(lesson, data, outcomes)


def _write_records(lesson: Lesson, score: dict[str, Any], outcomes: dict[str, Any]) -> Path | None:
    """Write the lesson's ``mutation-score.json`` and ``mutation-outcomes.json`` (each atomically); the score
    file's path, or None when the lesson folder is read-only (an installed course)."""
    path = lesson.folder / SCORE_FILE
    try:
        atomic_write_text(path, json.dumps(score, indent=1) + "\n")
        atomic_write_text(lesson.folder / OUTCOMES_FILE, json.dumps(outcomes, indent=0) + "\n")
    except OSError:
        return None
    return path


#: ``mutation-outcomes.json``'s list of the held-out mutants shown before its first sample was graded again.
SHOWN_KEY = "held_out_shown_before"


def recorded_first_sample(lesson: Lesson) -> set[str]:
    """The keys of the mutants the lesson's recorded first sample graded (``mutation-outcomes.json``)."""
    rows = read_json_object(lesson.folder / OUTCOMES_FILE).get("mutants", [])
    return {row["key"] for row in rows if isinstance(row, dict) and "key" in row}


def recorded_held_out(lesson: Lesson) -> set[str]:
    """The keys of every mutant a recorded held-out sample of the lesson has shown (the latest one's, and
    those it lists as ``earlier``): once its survivors were looked at, a held-out mutant is tuned, so the
    next held-out sample leaves them out (issue 37)."""
    outcomes = read_json_object(lesson.folder / OUTCOMES_FILE)
    section = outcomes.get("held_out") or {}
    keys = {row["key"] for row in section.get("mutants", []) if isinstance(row, dict) and "key" in row}
    earlier = [*section.get("earlier", []), *outcomes.get(SHOWN_KEY, [])]
    return keys | {key for key in earlier if isinstance(key, str)}


def write_held_out(lesson: Lesson, found: LessonMutation, measured: dict[str, str] | None = None) -> Path | None:
    """Record a held-out run (:func:`held_out_sample`) as the ``held_out`` section of the lesson's
    ``mutation-score.json`` (its counts, score, raw rate, uncovered survivors, seed, date, fingerprint) and
    ``mutation-outcomes.json`` (every mutant's outcome, by key, and as ``earlier`` the keys of the held-out
    samples recorded before it, which it left out); the first sample's figures stay. None when
    the lesson has no recorded first sample (a held-out sample is drawn after it) or its folder is read-only.
    """
    from ros2course.grade.fingerprint import measurement  # noqa: PLC0415 - reads the course's files

    score, outcomes = read_json_object(lesson.folder / SCORE_FILE), read_json_object(lesson.folder / OUTCOMES_FILE)
    if not score or not outcomes:
        return None
    measured = measured or measurement(lesson)
    section = _summary(found)
    section.update(date=measured["date"], fingerprint=measured["fingerprint"], **course_part(measured),
                   survivors=found.uncovered())
    section["earlier"] = held_out_history(score)  # a new sample never hides what the ones before it scored
    score.pop(EARLIER_KEY, None)
    score["held_out"] = section
    rows = _outcome_rows(found)
    earlier = sorted(recorded_held_out(lesson) - {row["key"] for row in rows})  # left out of this sample
    outcomes["held_out"] = {"fingerprint": measured["fingerprint"], "date": measured["date"], "seed": found.seed,
                            **({"family": found.family} if found.family != UNIVERSALMUTATOR else {}),
                            "mutants": rows, **({"earlier": earlier} if earlier else {})}
    return _write_records(lesson, score, outcomes)


def course_part(record: dict) -> dict[str, str]:
    """``{"course_fingerprint": ...}`` from a measurement or a recorded run, {} when it has none (runs recorded
    before course fingerprints were: :func:`ros2course.grade.fingerprint.course_fingerprint`)."""
    return {"course_fingerprint": record["course_fingerprint"]} if record.get("course_fingerprint") else {}


#: ``mutation-score.json``'s key for the figures of held-out samples drawn before its first sample was measured
#: again (a new first sample drops the held-out section; :func:`held_out_history` keeps what it scored).
EARLIER_KEY = "held_out_earlier"


def held_out_history(score: dict) -> list[dict]:
    """The figures of every held-out sample recorded in ``score`` (a ``mutation-score.json`` object), oldest
    first: each earlier one's ``{seed, date, fingerprint, graded, counted, killed, score}`` (and ``family`` when
    its mutants are not universalmutator's; ``score`` None when
    nothing was counted), then the current one's. [] when none was drawn. Drawing a new held-out sample keeps
    this list (issue 37: once looked at, a held-out sample is tuned; the figures before it still stand)."""
    held, before = score.get("held_out"), list(score.get(EARLIER_KEY, []))
    if not isinstance(held, dict) or not held.get("graded"):
        return before + (list(held.get("earlier", [])) if isinstance(held, dict) else [])
    counted = held.get("graded", 0) - held.get("killed_by_build", 0) - held.get("triaged", 0)
    return [*before, *held.get("earlier", []), {"seed": held.get("seed"), "date": held.get("date"),
                                       **({"family": held["family"]} if held.get("family", UNIVERSALMUTATOR)
                                          != UNIVERSALMUTATOR else {}),
                                       "fingerprint": held.get("fingerprint"), **course_part(held),
                                       "graded": held.get("graded"),
                                       "counted": counted, "killed": held.get("killed"),
                                       "score": held.get("killed", 0) / counted if counted > 0 else None}]


#: Below this many counted mutants a score is too small to judge a grader by (issue 37).
MIN_COUNTED = 20


@dataclasses.dataclass(frozen=True)
class PooledHeldOut:
    """Every held-out sample graded under one grader fingerprint, taken together (issue 37).

    A lesson whose held-out samples are drawn one after another could be shown by its best one; the pooled
    figure counts them all: ``killed / counted`` over ``samples`` samples, ``seeds`` in the order drawn.
    """

    samples: int
    killed: int
    counted: int
    seeds: tuple[int | None, ...]

    @property
    def score(self) -> float | None:
        """killed / counted, None when nothing was counted."""
        return self.killed / self.counted if self.counted > 0 else None


def pooled_held_out(score: dict, fingerprint: str) -> PooledHeldOut | None:
    """The held-out samples of ``score`` (a ``mutation-score.json`` object, :func:`held_out_history`) graded
    under ``fingerprint``, pooled; None when none was."""
    same = [e for e in held_out_history(score)
            if e.get("fingerprint") == fingerprint and isinstance(e.get("counted"), int) and e.get("graded")]
    if not same:
        return None
    return PooledHeldOut(len(same), sum(int(e.get("killed") or 0) for e in same),
                         sum(int(e["counted"]) for e in same), tuple(e.get("seed") for e in same))


@dataclasses.dataclass
class RecordedScore:
    """A lesson's recorded mutation run (``mutation-score.json``), as the figures the doc and ``dev validate`` show.

    Attributes:
        counted: graded - killed by build - triaged (the score's denominator).
        tuned: killed / counted (triage applied), None when nothing counts.
        raw: killed / (graded - killed by build), before any triage, None when nothing was graded.
        stale: "" when measured under the lesson's current grader fingerprint, else why not, with the run's date.
        held_out: the held-out sample's figures (its ``tuned`` is the held-out score), None when none was drawn.
    """

    data: dict
    counted: int
    tuned: float | None
    raw: float | None
    stale: str
    held_out: RecordedScore | None = None

    @property
    def too_small(self) -> bool:
        """Fewer than :data:`MIN_COUNTED` counted mutants."""
        return self.counted < MIN_COUNTED

    @property
    def spent(self) -> bool:
        """A (held-out) draw that found no mutant to grade: every one was shown by an earlier sample."""
        return not self.data.get("graded")


def _figures(data: dict, now: str) -> RecordedScore:
    """Raises ValueError, KeyError or TypeError on a malformed record."""
    graded, by_build, triaged, killed = (int(data[k]) for k in ("graded", "killed_by_build", "triaged", "killed"))
    counted, judged = graded - by_build - triaged, graded - by_build
    recorded, when = data.get("fingerprint"), data.get("date", "?")
    stale = ("" if recorded == now else
             f"stale: graded on {when}, before grader fingerprints were recorded" if not recorded else
             f"stale: graded on {when} under grader fingerprint {recorded}, now {now}")
    return RecordedScore(data, counted, killed / counted if counted > 0 else None,
                         killed / judged if judged > 0 else None, stale)


def recorded_score(lesson: Lesson) -> RecordedScore | None:
    """The lesson's recorded mutation run (:func:`write_score`), or None when there is none or it is unreadable."""
    data = read_json_object(lesson.folder / SCORE_FILE)
    from ros2course.grade.fingerprint import grader_fingerprint  # noqa: PLC0415 - reads the course's files

    now = grader_fingerprint(lesson) if data else ""
    try:
        row = _figures(data, now)
    except (ValueError, KeyError, TypeError):
        return None
    try:
        row.held_out = _figures(data["held_out"], now) if isinstance(data.get("held_out"), dict) else None
    except (ValueError, KeyError, TypeError):
        row.held_out = None
    return row


def _share(value: float | None) -> str:
    return "n/a" if value is None else f"{100 * value:.0f} %"


def score_text(lesson: Lesson) -> str:
    """The lesson's last mutation score in a few words (a table cell): the raw kill rate, the score after
    triage and its counted denominator, ``too small`` below :data:`MIN_COUNTED`, the held-out sample's score
    when one was drawn (with every held-out sample under the current grader pooled, when there are two or
    more: :func:`pooled_held_out`), ``stale`` when the grader changed since
    (``"raw 62 %, triaged 100 % of 13 counted (too small); held-out 80 % of 25; stale"``), ``held-out: none left to
    draw`` when the last held-out draw found no mutant no earlier sample had shown, or ``"not measured"``."""
    row = recorded_score(lesson)
    if row is None:
        return "not measured"
    held = row.held_out
    if held is not None and held.spent:
        held_text = "; held-out: none left to draw"
    else:
        held_text = ("" if held is None else f"; held-out {_share(held.tuned)} of {held.counted}"
                     + (" (too small)" if held.too_small else "") + ("" if not held.stale or row.stale else " (stale)"))
    pooled = pooled_held_out(row.data, held.data.get("fingerprint") or "") if held is not None else None
    if pooled is not None and pooled.samples > 1 and not held.stale:
        held_text += f" (all {pooled.samples} under this grader: {_share(pooled.score)} of {pooled.counted})"
    return (f"raw {_share(row.raw)}, triaged {_share(row.tuned)} of {row.counted} counted"
            + (" (too small)" if row.too_small else "") + held_text + ("; stale" if row.stale else ""))


def describe_score(lesson: Lesson) -> str:
    """One line on the lesson's last mutation score (:func:`write_score`), or how to measure it."""
    how = f"ros2course dev mutate {lesson.id} --sample 30"
    row = recorded_score(lesson)
    if row is None:
        return f"{lesson.id}: grader strength not measured ({how})"
    data = row.data
    graded = (f"{data['graded']} of {data['generated']} mutants (a sample)" if data.get("sampled")
              else f"all {data['generated']} mutants")
    small = f"; {row.counted} counted mutants are too few to judge by (< {MIN_COUNTED})" if row.too_small else ""
    stale = f"; {row.stale}: {how}" if row.stale else ""
    left = f"; {len(data.get('survivors', []))} survivor(s) not triaged" if data.get("survivors") else ""
    held = row.held_out
    if held is None:
        held_text = "; no held-out sample"
    elif held.spent:
        held_text = ("; no held-out mutant left to draw (the first sample and earlier held-out samples showed every "
                     "one; a new figure would be tuned)")
    else:
        uncovered = len(held.data.get("survivors", []))
        held_text = (f"; held-out sample {_share(held.tuned)} ({held.data['killed']} of {held.counted} counted, "
                     f"{_share(held.raw)} raw, {uncovered} survivor(s) no rule covers"
                     + (", too few to judge by" if held.too_small else "")
                     + (f", {held.stale}" if held.stale and not row.stale else "") + ")")
    return (f"{lesson.id}: grader strength {_share(row.tuned)} after triage, {_share(row.raw)} raw "
            f"({data['killed']} of {row.counted} counted mutants killed; "
            f"{graded}, {data['triaged']} triaged, {data['killed_by_build']} killed by the build; "
            f"dev mutate {data.get('date', '?')}{left}{small}{held_text}{stale})")


def _item_lines(path: Path, section: str) -> list[int]:
    """The line of each item of ``section`` (``rules`` or ``survivors``) in the YAML file ``path`` ([] unreadable)."""
    try:
        loader = yaml.SafeLoader(path.read_text(encoding="utf-8"))
        try:
            root = loader.get_single_node()
        finally:
            loader.dispose()
    except (OSError, yaml.YAMLError):
        return []
    if not isinstance(root, yaml.MappingNode):
        return []
    for key, value in root.value:
        if isinstance(key, yaml.ScalarNode) and key.value == section and isinstance(value, yaml.SequenceNode):
            return [item.start_mark.line + 1 for item in value.value]
    return []


def reference_texts(lesson: Lesson, reference: Path | None = None,
                    config: MutationConfig | None = None) -> dict[str, str]:
    """``{workspace-relative file: text}`` of the files rules may cover: the lesson's files in ``reference`` (a
    reference workspace; default: the course's ``solutions/``, which holds them at the same paths), narrowed by
    ``files:`` when mutation.yaml gives it. A superset of what is mutated: the check it feeds is conservative."""
    root = reference if reference is not None else lesson.course.solutions
    config = config if config is not None else load_config(lesson)
    out: dict[str, str] = {}
    for top in lesson.workspace_paths:
        base = root / top
        paths = [base] if base.is_file() else sorted(base.rglob("*")) if base.is_dir() else []
        for path in paths:
            rel = path.relative_to(root).as_posix()
            if not path.is_file() or not _mutable(path.relative_to(root)) and not _mutable(path):
                continue
            if config.files is not None and not any(fnmatch.fnmatch(rel, glob) for glob in config.files):
                continue
            try:
                out[rel] = path.read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError):
                continue
    return out


def rule_conflicts(lesson: Lesson, config: MutationConfig | None = None, reference: Path | None = None) -> list[str]:
    """Each rule of the lesson's ``mutation.yaml`` that covers a line implementing a requirement of its
    ``contract.yaml`` (:func:`ros2course.lesson.contract.implements`), as ``mutation.yaml:LINE: rule ID covers
    FILE:N `text`, which implements requirement R (contract.yaml:M: names `term`)``, for the requirements a check
    grades (a ``not_graded`` one already says its breakage is unseen); [] without a contract;
    one problem naming the contract's first error when it does not load (no rule is then known to be safe).

    A rule covers a line when its matchers on the original (file, ``original``, ``block``, ``not_block``)
    hold there (:meth:`Rule.covers_line`): some mutant of that line could be triaged by it. A line the starter
    gives as is (:func:`starter_given_lines`) implements only the requirements whose ``code:`` marks it, never
    one by naming its terms: the learner does not write it. Issue 37: a rule
    is a kind of change outside the contract, so it may never reach what the contract asks for; the mutants of
    such a line are triaged, if at all, one by one (``survivors:``), each with its own reason.
    """
    from ros2course.lesson.contract import contract_path, implements, load_contract, requirement_lines  # noqa: PLC0415 - the contract reader only when rules are checked against a contract

    config = config if config is not None else load_config(lesson)
    if not config.rules:
        return []
    path = contract_path(lesson.folder)
    if not path.is_file():
        return []
    contract, errors = load_contract(path, lesson.id)
    if contract is None:
        # a contract that does not load cannot vouch for any rule: say so, never "no conflict" (issue 37)
        first = errors[0] if errors else None
        return [f"{triage_path(lesson)}:1: rules not checked against the contract: "
                + (f"{first.path}:{first.line}: {first.message}" if first is not None else f"{path} does not load")]
    rule_lines = _item_lines(triage_path(lesson), "rules")
    req_lines = requirement_lines(path)
    problems = []
    starters = {rel: path.read_text(encoding="utf-8", errors="replace").splitlines()
                for rel, path in _own_starter(lesson).items() if _mutable(path)}
    for rel, text in reference_texts(lesson, reference, config).items():
        lines = text.splitlines()
        given = starter_given_lines(tuple(lines), tuple(starters[rel])) if rel in starters else frozenset()
        for number, line in enumerate(lines, 1):
            for index, rule in enumerate(config.rules):
                if not rule.covers_line(rel, lines, number):
                    continue
                for requirement in contract.requirements:
                    if requirement.checks is None:
                        # a requirement the contract says no check can see (not_graded, with its reason): a
                        # rule triaging its lines' survivors says the same thing, and the table is where it is reviewed
                        continue
                    if number in given and requirement.code is None:
                        # a line the starter gives as is: the learner never writes it, so naming a term of a
                        # requirement does not make it that requirement's; a given line the lesson makes a
                        # requirement is marked with `code:` (the discovery loops of inspect-topics/params)
                        continue
                    why = implements(requirement, rel, line)
                    if why is not None:
                        where = rule_lines[index] if index < len(rule_lines) else 1
                        problems.append(f"{triage_path(lesson)}:{where}: rule {rule.id} covers {rel}:{number} "
                                        f"`{line.strip()}`, which implements requirement {requirement.id} "
                                        f"({path}:{req_lines.get(requirement.id, 1)}: {why})")
    return problems


def triage_problems(lesson: Lesson, every: list[Mutant] | None = None, reference: Path | None = None) -> list[str]:
    """What ``dev validate`` reports about the lesson's mutation triage and records, each with file and line:

    * a rule covering a line that implements a contract requirement (:func:`rule_conflicts`);
    * with ``every`` (every mutant generated now): a rule or an entry of ``mutation.yaml`` that matches none;
    * ``mutation-outcomes.json`` (or its ``held_out`` section) made under another grader fingerprint than the
      lesson's current one, or than its ``mutation-score.json``.

    A malformed ``mutation.yaml`` is one problem (its message names the field).
    """
    from ros2course.grade.fingerprint import grader_fingerprint  # noqa: PLC0415 - reads the course's files

    try:
        config = load_config(lesson)
    except LessonFormatError as exc:
        return [str(exc)]
    problems = rule_conflicts(lesson, config, reference)
    if every is not None:
        for section, items in (("rules", config.rules), ("survivors", config.survivors)):
            lines = _item_lines(triage_path(lesson), section)
            for index, item in enumerate(items):
                if not any(item.matches(m) for m in every):
                    what = f"rule {item.id}" if isinstance(item, Rule) else f"entry {item.describe()}"
                    problems.append(f"{triage_path(lesson)}:{lines[index] if index < len(lines) else 1}: "
                                    f"{what} matches no mutant of the reference")
    outcomes_path, score_path = lesson.folder / OUTCOMES_FILE, lesson.folder / SCORE_FILE
    outcomes, score = read_json_object(outcomes_path), read_json_object(score_path)
    if outcomes or score:
        now = grader_fingerprint(lesson)
        for part, record, path in (("", outcomes, outcomes_path), ("held_out", outcomes.get("held_out"), outcomes_path),
                                   ("", score, score_path), ("held_out", score.get("held_out"), score_path)):
            if not isinstance(record, dict) or not record:
                continue
            where = f"{path}:{_json_line(path, part)}: " + (f"{part}: " if part else "")
            recorded = record.get("fingerprint")
            if recorded != now:
                problems.append(f"{where}recorded under grader fingerprint {recorded or '(none)'} on "
                                f"{record.get('date', '?')}, the lesson's is {now} now: measure it again")
        if outcomes and score and outcomes.get("fingerprint") != score.get("fingerprint"):
            problems.append(f"{outcomes_path}:1: its fingerprint {outcomes.get('fingerprint')} is not that of "
                            f"{score_path.name} ({score.get('fingerprint')}): the two come from different runs")
    return problems


def _json_line(path: Path, key: str) -> int:
    """The line of ``"key":`` in a JSON file (1 when absent or ``key`` is empty)."""
    if not key:
        return 1
    try:
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if line.lstrip().startswith(f'"{key}":'):
                return number
    except OSError:
        pass
    return 1
