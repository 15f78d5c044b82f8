"""Graders: one module per lesson, a declaration of checks plus a ``grade()`` built from the kit.

A grader module defines ``CHECKS`` (list of :class:`ros2course.grade.checklist.Check`,
each naming the checks it ``needs``) and ``grade(session) -> None`` calling
the steps of :mod:`ros2course.kit`. How to write one: graders/README.md.
"""
