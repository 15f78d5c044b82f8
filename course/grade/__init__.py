"""The grading engine, its result model and the course validation."""
