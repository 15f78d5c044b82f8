"""The ament resource index, read through an explicit environment (never ``os.environ``).

``ament_index_python`` reads ``AMENT_PREFIX_PATH`` from the process-wide
``os.environ`` at call time. Graders look packages up in the learner's
overlay while other threads of the same grader use other environments (the
service lesson grades its server and client halves at once), so swapping
``os.environ`` around the call is not safe. These functions do the same
lookups on an environment passed in, following the index layout that
ament_index documents and ament_index_python implements
(``<prefix>/share/ament_index/resource_index/packages/<name>``, prefixes
searched in ``AMENT_PREFIX_PATH`` order, the first one wins).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

_PACKAGES = Path("share") / "ament_index" / "resource_index" / "packages"


def search_paths(env: Mapping[str, str]) -> list[Path]:
    """The prefixes of ``env["AMENT_PREFIX_PATH"]``, in order (empty entries dropped)."""
    return [Path(p) for p in env.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]


def package_prefix(package: str, env: Mapping[str, str]) -> Path | None:
    """The install prefix of ``package`` as ``ament_index_python.get_package_prefix`` finds it, or None."""
    for prefix in search_paths(env):
        if (prefix / _PACKAGES / package).is_file():
            return prefix
    return None


def package_share(package: str, env: Mapping[str, str]) -> Path | None:
    """``<prefix>/share/<package>`` (``get_package_share_directory``), or None when not indexed."""
    prefix = package_prefix(package, env)
    return None if prefix is None else prefix / "share" / package


def packages_with_prefixes(env: Mapping[str, str]) -> dict[str, Path]:
    """Every indexed package -> its prefix (``get_packages_with_prefixes``: the first prefix wins)."""
    found: dict[str, Path] = {}
    for prefix in search_paths(env):
        folder = prefix / _PACKAGES
        if folder.is_dir():
            for entry in sorted(folder.iterdir()):
                if entry.is_file() and not entry.name.startswith("."):
                    found.setdefault(entry.name, prefix)
    return found
