"""Graders: one module per lesson, each a short composition of ``course`` probes.

A grader module defines ``CHECKS`` (list of :class:`course.grading.Check`)
and ``grade(session: course.grading.GradingSession) -> None``.
"""
