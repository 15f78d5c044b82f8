"""hello-node as the instructor grades it: the public grader's checks, then one hidden and one shown after the due date.

The public grader is the extended course's, importable from ``graders/parent/`` of the merged course
(:func:`ros2course.lesson.courses.course_folder`).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from ros2course.kit import Check, GradingSession

from .parent.hello_node import CHECKS as PUBLIC, PACKAGE, grade as grade_public

CHECKS = [
    *PUBLIC,
    Check("license", "package.xml declares the Apache-2.0 license", 1,
          "put <license>Apache-2.0</license> in package.xml", visibility="hidden"),
    Check("maintainer", "package.xml names a maintainer with an e-mail address", 1,
          "add <maintainer email=\"you@example.com\">Your Name</maintainer> to package.xml", visibility="after_due"),
]


def grade(s: GradingSession) -> None:
    """The public checks, then the package.xml's license and maintainer."""
    grade_public(s)
    try:  # the hand-in's package.xml, read as XML (a parse error loses both checks, with the reason)
        root = ET.parse(s.workspace_root / "src" / PACKAGE / "package.xml").getroot()
    except (OSError, ET.ParseError) as exc:
        s.record("license", False, f"package.xml cannot be read: {exc}", "a package.xml ROS tools can read")
        s.record("maintainer", False, f"package.xml cannot be read: {exc}", "a package.xml ROS tools can read")
        return
    licenses = [(item.text or "").strip() for item in root.findall("license")]
    s.record("license", licenses == ["Apache-2.0"], f"licenses: {', '.join(licenses) or 'none'}", "Apache-2.0")
    emails = [item.get("email", "") for item in root.findall("maintainer") if item.get("email")]
    s.record("maintainer", bool(emails), f"maintainer e-mails: {', '.join(emails) or 'none'}",
             "a <maintainer> with an email attribute")
