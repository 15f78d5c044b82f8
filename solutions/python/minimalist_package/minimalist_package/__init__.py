"""The minimalist package: a folder with an ``__init__.py`` is a Python package.

Whatever this file imports is what ``import minimalist_package`` offers, so
users write ``from minimalist_package import MinimalistClass`` without knowing
which module the class lives in.
"""
from minimalist_package._minimalist_class import MinimalistClass

__all__ = ["MinimalistClass"]
