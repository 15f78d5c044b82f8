"""Rendering results: the console table and the gradebook."""
