"""The grading engine: sessions, checks, verdicts, a lesson regraded, a grader fingerprint."""
