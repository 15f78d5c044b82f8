"""Reading what a learner's node said: the words of its log records (``/rosout``) as a lesson asks for them.

A lesson asks for a record *naming* something (a goal's status, a state): the grader accepts any wording
and case around it, but the name must stand as a word of its own. A substring search accepts what does not
name it: ``'unsuccessful'`` holds ``'succe'``, ``'XXSUCCEEDEDXX'`` holds ``'SUCCEEDED'``.

Kept out of :mod:`ros2course.kit.actions` on purpose: a grader's figures are fingerprinted per kit module
it imports (:mod:`ros2course.grade.fingerprint`), and this step is used only by the action clients'
graders (actions-client, nav2-custom-nodes), not by the action servers'.
"""

from __future__ import annotations

import re

from ros2course.kit.actions import STATUS_NAMES


def names_status(text: str, status: int) -> bool:
    """Whether the log record ``text`` names the goal status ``status`` (an action_msgs/msg/GoalStatus value,
    e.g. 4 for SUCCEEDED) as a word: a word starting with the name's first five letters, in any case and
    spelling (``SUCCEEDED``, ``succeeded``, ``Success``, ``cancelled``, ``STATUS_ABORTED``); never the letters
    inside another word (``unsuccessful``, ``XXSUCCEEDEDXX``).

    Raises:
        KeyError: ``status`` is not a GoalStatus value (0-6).
    """
    stem = re.escape(STATUS_NAMES[status][:5])
    return re.search(rf"(?<![A-Za-z0-9]){stem}", text, re.IGNORECASE) is not None
