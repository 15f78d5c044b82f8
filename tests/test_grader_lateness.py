"""A grader that is late must not fail correct code.

On a loaded machine (CI: two cores, two gradings at once, ``grade``'s isolation) the grader can see a
message long after it was sent. actions-server cancels a 1.6 s goal after its third feedback message;
CI once saw that goal SUCCEED before the cancel request reached the server, and the reference lost
``cancel_accepted`` and ``canceled``; it preempts a 1.8 s goal the same way. Here the lateness is made
certain: the grader's waits for a third feedback message return only once the goal has ended. The
server answers the cancel with ERROR_GOAL_TERMINATED, as it must, and the grader tries again with a new
goal, cancelled (preempted) at its first feedback message: full marks, each retry said in what was
observed.
"""

from __future__ import annotations

import pytest

from ros2course.grade.engine import grade_lesson, load_grader
from ros2course.grade.results import Status
from ros2course.dev.validate import reference_workspace
from ros2course.kit import wait_until
from ros2course.lesson.catalog import load_catalog

pytestmark = [pytest.mark.ros, pytest.mark.timeout(600)]


def test_actions_server_grader_late_for_the_cancel_tries_again(tmp_path, monkeypatch):
    lesson = load_catalog().get("actions-server")
    steps = load_grader(lesson.grader).steps  # graders/_actions_server.py, the lesson's steps
    original = steps._wait_feedback
    late = []

    def wait_past_the_end(s, client, goal, count, node, timeout):
        """A wait for three messages (the cancel's, the preemption's) returns after the goal's result."""
        seen = original(s, client, goal, count, node, timeout)
        if count == 3:
            late.append(goal)
            wait_until(lambda: goal.result_future is not None and goal.result_future.done(),
                       steps.CANCEL_DISTANCE / steps.SPEED + steps.GOAL_SLACK)
        return seen

    monkeypatch.setattr(steps, "_wait_feedback", wait_past_the_end)
    result = grade_lesson(lesson, reference_workspace(lesson, tmp_path / "ws"), log_dir=tmp_path / "log")
    assert len(late) == 2, "the cancel and the preemption waited for three feedback messages"
    assert result.status == Status.PASSED, [(c.id, c.observed) for c in result.checks if not c.passed] or result.message
    observed = {c.id: c.observed for c in result.checks}
    assert "tried again after: the goal" in observed["cancel_accepted"], observed["cancel_accepted"]
    assert "had SUCCEEDED when the cancel request arrived" in observed["cancel_accepted"]
    assert "tried again after: the goal" in observed["preempted"], observed["preempted"]
    assert "had reached its end" in observed["preempted"]
