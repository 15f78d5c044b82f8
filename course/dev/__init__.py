"""The course author's tools (``ros2course dev ...``): validate, mutate, repeat, strength, contract
coverage, batch parity and the lesson scaffold.

They sit beside the CLI, above the grading engine and the batch grader they drive; nothing that grades
a learner or a class imports them (the import-linter contract ``grading-without-dev-tools`` in
pyproject.toml).
"""
