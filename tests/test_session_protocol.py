"""The grader's door (issue 38): ``ros2course.kit.Session`` lists what graders and kit steps use of their
session, and the engine's GradingSession provides each member with the same signature.

Graders and kit steps are read (AST): every attribute used on a parameter annotated as the session
(``s: Session``, ``s: GradingSession``) or on ``self.s`` must be a member of the Protocol, so a grader
cannot start to lean on the engine's inside (its timings, closers, recorder) unnoticed.
"""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import pytest

from ros2course.grade.session import GradingSession
from ros2course.kit.session_protocol import MEMBERS, Session

ROOT = Path(__file__).resolve().parents[1]
SOURCES = sorted([*(ROOT / "graders").glob("*.py"), *(ROOT / "course" / "kit").glob("*.py")])
SESSION_TYPES = {"Session", "GradingSession", "kit.Session", "kit.GradingSession", "Session | None",
                 "GradingSession | None"}


def session_uses(source: str) -> list[tuple[int, str]]:
    """``(line, member)`` for every attribute read on a session in ``source``: on a function parameter
    annotated as the session, or on ``self.s``."""
    found = []
    for func in ast.walk(ast.parse(source)):
        if not isinstance(func, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            continue
        args = [*func.args.posonlyargs, *func.args.args, *func.args.kwonlyargs]
        names = {a.arg for a in args if a.annotation is not None and ast.unparse(a.annotation) in SESSION_TYPES}
        for node in ast.walk(func):
            if not isinstance(node, ast.Attribute):
                continue
            value = node.value
            if isinstance(value, ast.Name) and value.id in names:
                found.append((node.lineno, node.attr))
            elif (isinstance(value, ast.Attribute) and value.attr == "s" and isinstance(value.value, ast.Name)
                  and value.value.id == "self"):
                found.append((node.lineno, node.attr))
    return sorted(set(found))


def test_the_reader_finds_session_members() -> None:
    source = ("def f(s: Session, t):\n    s.record('a')\n    t.x\n"
              "class C:\n    def g(self):\n        return self.s.launch\n")
    assert session_uses(source) == [(2, "record"), (6, "launch")]


@pytest.mark.parametrize("path", SOURCES, ids=[f"{p.parent.name}/{p.name}" for p in SOURCES])
def test_graders_and_kit_steps_use_only_the_door(path: Path) -> None:
    outside = [f"line {line}: s.{name}" for line, name in session_uses(path.read_text()) if name not in MEMBERS]
    assert not outside, (f"{path.name} uses session members outside ros2course.kit.Session: {outside} (add the "
                         "member to the Protocol, documented, or use a kit step)")


def test_the_grading_session_provides_every_member_with_its_signature() -> None:
    hints = {name: value for name, value in Session.__annotations__.items()}
    for name in MEMBERS:
        ours = Session.__dict__.get(name)
        if name in hints:  # a data attribute: GradingSession sets it in __init__, or reads it from a part (a property)
            assert (isinstance(inspect.getattr_static(GradingSession, name, None), property)
                    or f"self.{name} =" in inspect.getsource(GradingSession.__init__)), name
            continue
        theirs = inspect.getattr_static(GradingSession, name)
        if isinstance(ours, property):
            assert isinstance(theirs, property), f"{name} is a property of Session, not of GradingSession"
            continue
        theirs = getattr(theirs, "__wrapped__", theirs)  # contextmanager-made part/phase
        want = [(p.name, p.kind, p.default) for p in inspect.signature(ours).parameters.values()]
        got = [(p.name, p.kind, p.default) for p in inspect.signature(theirs).parameters.values()]
        assert got == want, f"GradingSession.{name}{inspect.signature(theirs)} != Session.{name}{inspect.signature(ours)}"


def test_every_member_is_documented() -> None:
    for name in MEMBERS:
        if name in Session.__annotations__:
            assert f"{name}:" in Session.__doc__, name
        else:
            member = Session.__dict__[name]
            doc = (member.fget if isinstance(member, property) else member).__doc__
            assert doc and len(doc.strip()) > 20, name
