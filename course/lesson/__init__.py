"""The lesson catalog: lessons, starters, the learner's progress."""
