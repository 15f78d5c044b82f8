"""This course's graders: one module per lesson."""
