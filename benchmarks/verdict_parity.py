"""Every case's verdict before and after a change of the engine: the table issue 23 asks for.

Each side is a folder of ``<lesson>.json`` files, one ``ros2course dev validate --json LESSON``
per lesson, graded on that side's checkout (reference, starter and every wrong solution).
Cases are matched by (lesson, case); a case compares equal when its verdict (as the case
expects, or not), its status, the checks it lost and its points agree on the checks both sides
have (a check a later lesson change added is named, not counted as a difference). A check that
``--until-settled`` left unjudged on either side is no verdict and is compared on neither (issue 38's
table: which checks a stopped grading reached depends on a part graded at the same time). Prints a
markdown table and, on stderr, how many cases compare equal; exit status 1 when any differs::

    python benchmarks/verdict_parity.py BEFORE_DIR AFTER_DIR > docs/issue-23-verdicts.md

Issue 23's table was made from e6e5ab0 (landed main when the issue was filed; its engine is the
import package ``course``: ``python -c "import sys; sys.argv=['ros2course', 'dev', 'validate', '--json',
LESSON]; from course.cli import main; main()"`` in a worktree of it) and from the refactored tree.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ros2course.grade.checklist import STOPPED_SETTLED


def load(folder: Path) -> dict[tuple[str, str], dict]:
    """``{(lesson, case): outcome}`` from a folder of ``dev validate --json`` outputs (a file that is not JSON is skipped)."""
    out = {}
    for path in sorted(folder.glob("*.json")):
        try:
            rows = json.loads(path.read_text(encoding="utf-8") or "[]")
        except json.JSONDecodeError:
            continue
        for row in rows:
            result = row.get("result") or {}
            checks = {c["id"]: c for c in result.get("checks", [])}
            out[(row["lesson"], row["case"])] = {
                "ok": row["ok"], "score": result.get("score"), "max": result.get("max_score"),
                "status": result.get("status"), "checks": checks,
                "lost": sorted(i for i, c in checks.items() if not c.get("passed"))}
    return out


def cell(outcome: dict | None) -> str:
    """One side of a row: ``as expected: 12/14 (lost: rate)``."""
    if outcome is None:
        return "—"
    score = f"{outcome['score']:g}/{outcome['max']:g}" if outcome["score"] is not None else outcome["status"]
    lost = f" (lost: {', '.join(outcome['lost'])})" if outcome["lost"] else ""
    return f"{'as expected' if outcome['ok'] else 'NOT as expected'}: {score}{lost}"


#: What a check left unjudged by ``dev validate --until-settled`` says: which checks a stopped grading reached
#: before its stop depends on how far a part graded at the same time (kit.parts.at_once) had got, so such a
#: check is no verdict and is compared on neither side.
UNJUDGED = STOPPED_SETTLED


def unjudged(outcome: dict) -> set[str]:
    """The checks of ``outcome`` that ``--until-settled`` left unjudged."""
    return {i for i, c in outcome["checks"].items() if not c.get("passed") and UNJUDGED in c.get("observed", "")}


def compare(before: dict, after: dict) -> str:
    """``same``, ``same on the common checks; new check X``, ``same on the checks judged on both sides``, or
    ``DIFFERENT``: a check only one side's ``--until-settled`` left unjudged is compared on neither (nor are the
    points then, which such checks change), every other check by its verdict."""
    common = set(before["checks"]) & set(after["checks"])
    skipped = (unjudged(before) ^ unjudged(after)) & common  # unjudged on both sides: the same on both
    common -= skipped

    def judged(o: dict) -> tuple:
        return (o["ok"], sorted(set(o["lost"]) & common), round(sum(o["checks"][c]["points"] for c in common), 3),
                *(() if skipped else (o["status"],)))

    if judged(before) != judged(after):
        return "DIFFERENT"
    added = sorted(set(after["checks"]) - common - skipped)
    gone = sorted(set(before["checks"]) - common - skipped)
    if not (added or gone or skipped):
        return "same"
    return ("same on the checks judged on both sides" if skipped else "same on the common checks") + \
        (f" ({len(skipped)} left unjudged by --until-settled on one side)" if skipped else "") + \
        (f"; new check {', '.join(added)}" if added else "") + (f"; check gone: {', '.join(gone)}" if gone else "")


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print("usage: verdict_parity.py BEFORE_DIR AFTER_DIR", file=sys.stderr)
        return 2
    before, after = load(Path(argv[0])), load(Path(argv[1]))
    counts: dict[str, int] = {}
    rows = []
    for key in sorted(set(before) | set(after)):
        b, a = before.get(key), after.get(key)
        tag = compare(b, a) if b and a else ("new case" if a else "case gone")
        kind = tag.split(";")[0].split(" (")[0]
        counts[kind] = counts.get(kind, 0) + 1
        rows.append(f"| {key[0]} | {key[1]} | {cell(b)} | {cell(a)} | {tag} |")
    print(", ".join(f"{n} {tag}" for tag, n in sorted(counts.items())), file=sys.stderr)
    print("| lesson | case | before | after | comparison |\n|---|---|---|---|---|")
    print("\n".join(rows))
    return 1 if counts.get("DIFFERENT") else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
