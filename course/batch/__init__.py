"""Grading a whole class: archives, sandboxed workers, Gradescope."""
