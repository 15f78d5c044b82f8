"""A lesson's grader is a short declaration (issue 38): ``CHECKS`` plus a ``grade()`` on the kit, at most
:data:`MAX_CODE_LINES` lines of code, reaching ROS only through the kit and its session (no rclpy import).

Long procedures live as one function per check in the lesson's own helper (``graders/_<name>.py``, the
placement rule in ``ros2course.kit``'s docstring) or as kit steps another lesson can call."""

from __future__ import annotations

import ast
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
