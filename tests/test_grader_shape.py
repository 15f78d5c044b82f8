"""A lesson's grader is a short declaration (issue 38): ``CHECKS`` plus a ``grade()`` on the kit, at most
:data:`MAX_CODE_LINES` lines of code, reaching ROS only through the kit and its session (no rclpy import).

Long procedures live as one function per check in the lesson's own helper (``graders/_<name>.py``, the
placement rule in ``ros2course.kit``'s docstring) or as kit steps another lesson can call."""

from __future__ import annotations

import ast
import re
import io
import tokenize
from pathlib import Path

import pytest

GRADERS = Path(__file__).resolve().parents[1] / "graders"
#: Lines of code (no docstring, comment or blank line) a lesson grader may hold (issue 38).
MAX_CODE_LINES = 180


def code_lines(source: str) -> int:
    """Lines holding code in ``source``: docstrings (of the module, classes and functions), comments and blank
    lines are not counted; a statement over several lines counts each of them."""
    tree = ast.parse(source)
    docstrings: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
                docstrings.update(range(first.lineno, first.end_lineno + 1))
    lines: set[int] = set()
    skipped = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT, tokenize.ENDMARKER}
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type not in skipped:
            lines.update(line for line in range(token.start[0], token.end[0] + 1) if line not in docstrings)
    return len(lines)


def rclpy_imports(source: str) -> list[int]:
    """Line numbers of ``import rclpy...`` / ``from rclpy... import`` statements in ``source`` (anywhere, also
    inside functions)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import) and any(a.name == "rclpy" or a.name.startswith("rclpy.") for a in node.names):
            found.append(node.lineno)
        elif isinstance(node, ast.ImportFrom) and node.module and (node.module == "rclpy"
                                                                   or node.module.startswith("rclpy.")):
            found.append(node.lineno)
    return found


def test_the_counter_leaves_out_docstrings_comments_and_blank_lines() -> None:
    source = '"""Module.\n\nMore."""\n\n# a comment\nX = (1,\n     2)\n\n\ndef f():\n    """Doc."""\n    return X  # why\n'
    assert code_lines(source) == 4  # X = (1, / 2) / def f(): / return X
    assert rclpy_imports("import rclpy.qos\ndef f():\n    from rclpy.node import Node\nimport rclpyx\n") == [1, 3]


LESSON_GRADERS = sorted(p for p in GRADERS.glob("*.py") if not p.name.startswith("_"))


@pytest.mark.parametrize("grader", LESSON_GRADERS, ids=[p.stem for p in LESSON_GRADERS])
def test_a_lesson_grader_is_a_short_declaration_without_rclpy(grader: Path) -> None:
    source = grader.read_text()
    assert code_lines(source) <= MAX_CODE_LINES, (
        f"{grader.name}: {code_lines(source)} lines of code (at most {MAX_CODE_LINES}): move long procedures into "
        f"one function per check in graders/_{grader.stem}.py, or into a kit step another lesson can use")
    assert not rclpy_imports(source), (
        f"{grader.name} imports rclpy at line(s) {rclpy_imports(source)}: reach ROS through the kit")


KIT = GRADERS.parent / "course" / "kit"
#: A grader that reuses another lesson's grader because it is the same lesson in another client library:
#: cpp-node is print-forever-node in C++ (tutorial ch. 12-13 and 27), graded by the same steps.
TWINS = {"cpp_node": "print_forever_node"}


def relative_imports(source: str) -> set[str]:
    """Modules of the graders package ``source`` imports (``from . import _x``, ``from ._x import y``)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            found.update([node.module] if node.module else [a.name for a in node.names])
    return found


def lessons_using(helper: str) -> set[str]:
    """Lesson graders that import ``helper`` (a ``graders/_x.py``), directly or through other helpers."""
    users: set[str] = set()
    for grader in LESSON_GRADERS:
        seen, todo = set(), [grader.stem]
        while todo:
            module = todo.pop()
            if module in seen:
                continue
            seen.add(module)
            todo.extend(m for m in relative_imports((GRADERS / f"{module}.py").read_text()) if m.startswith("_"))
        if helper in seen:
            users.add(grader.stem)
    return users


def test_the_placement_rule_holds() -> None:
    """ros2course.kit's placement rule (issues 23 and 38): a ``graders/_x.py`` serves one lesson, a step two
    lessons use lives in the kit; a lesson grader imports no other lesson's grader (but its twin's); every kit
    module serves a grader or another kit module, or it goes."""
    helpers = sorted(p.stem for p in GRADERS.glob("_*.py") if p.stem != "__init__")
    shared = {h: sorted(users) for h in helpers if len(users := lessons_using(h)) > 1}
    assert not shared, f"helpers more than one lesson imports (move them into ros2course.kit): {shared}"
    unused = [h for h in helpers if not lessons_using(h)]
    assert not unused, f"helpers no lesson imports: {unused}"
    lessons = {p.stem for p in LESSON_GRADERS}
    crossing = {g.stem: sorted(m for m in relative_imports(g.read_text()) if m in lessons and TWINS.get(g.stem) != m)
                for g in LESSON_GRADERS}
    assert not {k: v for k, v in crossing.items() if v}, f"graders importing another lesson's grader: {crossing}"
    sources = {p: p.read_text() for p in (*GRADERS.glob("*.py"), *KIT.glob("*.py"))}
    kit_modules = sorted(p.stem for p in KIT.glob("*.py") if p.stem != "__init__")
    idle = [m for m in kit_modules
            if not any(re.search(rf"ros2course\.kit\.{m}\b|from ros2course\.kit import [^\n]*\b{m}\b", text)
                       for path, text in sources.items() if path != KIT / f"{m}.py")]
    assert not idle, f"kit modules no grader or kit module imports (remove them): {idle}"
