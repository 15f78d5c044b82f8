"""The course checks itself: every lesson's reference gets full marks, its starter does not,
and every wrong solution in tests/fixtures loses the points of the check that names its bug."""

from __future__ import annotations

import json

import pytest

from course.lesson import load_catalog


@pytest.mark.ros
@pytest.mark.parametrize("lesson_id", load_catalog().ids())
def test_dev_validate(lesson_id, cli):
    proc = cli("dev", "validate", lesson_id, "--json", timeout=900)
    assert "Traceback" not in proc.stderr, proc.stderr
    outcomes = json.loads(proc.stdout)
    cases = {o["case"] for o in outcomes}
    assert {"reference", "starter"} <= cases
    wrong = [o for o in outcomes if o["case"] not in ("reference", "starter")]
    assert wrong, f"{lesson_id} has no wrong-solution fixtures"
    bad = [f"{o['case']}: expected {o['expected']}, got {o['got']}" for o in outcomes if not o["ok"]]
    assert not bad, "\n".join(bad)
    assert proc.returncode == 0
