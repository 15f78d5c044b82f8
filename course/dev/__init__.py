"""The course author's tools (``ros2course dev ...``): validate, mutate, repeat, strength, contract
coverage, batch parity and the lesson scaffold.

They sit beside the CLI, above the grading engine and the batch grader they drive; nothing that grades
a learner or a class imports them (the import-linter contract ``grading-without-dev-tools`` in
pyproject.toml).
"""


def first_line(text: str | None, cap: int = 300) -> str:
    """The first line of ``text`` (a result's message, a traceback's last words), at most ``cap`` characters;
    "" for None or an empty text. How the author's tools quote a grading's message in a one-line outcome."""
    return (text or "").strip().partition("\n")[0][:cap]
