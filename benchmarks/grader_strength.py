"""Grader strength per lesson: ``ros2course dev mutate --sample 30 --seed 1``, written to docs/grader-strength.md.

For each lesson (default: every lesson of the course) it runs the mutation
analysis of :mod:`ros2course.dev.mutate` on a seeded sample of the lesson's
mutants (universalmutator), graded through the batch engine, and writes one
table row per lesson: mutants generated, graded (sampled or all), killed by the
build, killed, survived, triaged (``chapters/<lesson>/mutation.yaml``), score
and wall time. A lesson not run this time keeps the row of its last run (its
``mutation-score.json``, with that run's date and course version). Results are cached
in ``--out`` (a second run grades only new mutants)::

    python benchmarks/grader_strength.py [LESSON ...] [--sample 30] [--seed 1] [--jobs 2] [--out DIR]
    python benchmarks/grader_strength.py print-forever-node --speedup   # also times --jobs 1 vs --jobs N
    python benchmarks/grader_strength.py --readme   # only README.md's lesson table, from the recorded scores
    python benchmarks/grader_strength.py LESSON... --held-out 30 [--held-out-seed 2]   # the held-out sample

``--held-out N`` grades, for each lesson already measured, a second seeded sample of N mutants disjoint
from its first (:func:`ros2course.dev.mutants.held_out_sample`), triaged with ``mutation.yaml`` as it is
(rules and entries; nothing is added), and records it beside the first (``held_out`` in
``mutation-score.json`` and ``mutation-outcomes.json``); the doc shows both scores.

``--speedup`` grades the lesson's sample twice more without the cache (``--jobs 1`` then
``--jobs N``) and reports the parallel speed-up.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rich.console import Console  # noqa: E402

from ros2course.dev.mutate import mutate_lessons, render  # noqa: E402
from ros2course.dev.parity import case_workspace  # noqa: E402
from ros2course.dev import mutants as mut  # noqa: E402
from ros2course.dev.mutants import SCORE_FILE, lesson_files  # noqa: E402
from ros2course.dev.repeat import render_steadiness, repeat_lessons  # noqa: E402
from ros2course.dev.strength import steadiness_text, write_steadiness  # noqa: E402
from ros2course.dev.validate import with_lessons_table  # noqa: E402
from ros2course.lesson.catalog import load_catalog  # noqa: E402
from ros2course.ros import env as env_mod  # noqa: E402


def _pct(value) -> str:
    return "n/a" if value is None else f"{100 * value:.0f} %"


def _row(f, sample: int) -> str:
    """A row for a lesson just run whose score file could not be written (a read-only course)."""
    counted = len(f.graded) - f.count("killed by build") - f.triaged
    graded = (f"{len(f.graded)} of {f.generated - f.set_aside} (seeded sample)" if f.sampled
              else f"{len(f.graded)} (all)") + (f"; {f.set_aside} set aside" if f.set_aside else "")
    return (f"| {f.lesson} | {f.generated} | {graded} | {f.count('killed by build')} | {f.count('killed')} | "
            f"{f.count('survived')} | {f.triaged} ({f.by_rule}) | {f.count('timed out') + f.count('grader error')} | "
            f"{_pct(f.raw)} | {counted} | {_pct(f.score)} | not recorded | current (this run, not recorded) | "
            f"{steadiness_text(load_catalog().get(f.lesson))} |")


def _earlier_held_out(history: list[dict], fingerprint: str | None) -> list[str]:
    """One phrase per earlier held-out sample (:func:`ros2course.dev.mutants.held_out_history`'s entries):
    its seed, date and score, and whether it was graded under another grader than ``fingerprint``."""
    return [f"seed {e.get('seed', '?')} ({e['family'] + ', ' if e.get('family') else ''}{e.get('date', '?')}): " + (
        f"{_pct(e['score'])} of {e.get('counted')}" if e.get("score") is not None else "none counted")
        + ("" if e.get("fingerprint") == fingerprint else " under an earlier grader")
        for e in history]


def _why_too_few(data: dict, sample: int = 30) -> str:
    """Why a sample counted fewer than ``mut.MIN_COUNTED`` mutants, from its record (``graded``, ``pool``,
    ``killed_by_build``, ``triaged``): fewer left to draw than the sample's size, mutants a broken build
    caught before any check (a C++, CMake or interface file), survivors triaged as equivalent by kind."""
    graded = data.get("graded", 0)
    why = []
    if graded < data.get("sample", sample):
        why.append(f"only {graded} were left to draw" if data.get("pool") == graded else f"{graded} graded")
    if data.get("killed_by_build"):
        why.append(f"{data['killed_by_build']} of {graded} broke the build (caught before any check)")
    if data.get("triaged"):
        why.append(f"{data['triaged']} triaged as equivalent")
    return "; ".join(why)


def _too_small(counted: int, data: dict) -> str:
    """`` (too small to judge: 12 < 20; why)``: the phrase a row with fewer counted mutants than
    ``mut.MIN_COUNTED`` carries (issue 37: the row says why the lesson cannot reach 20)."""
    why = _why_too_few(data)
    return f" (too small to judge: {counted} < {mut.MIN_COUNTED}{'; ' + why if why else ''})"


def _held_out_cell(row) -> str:
    """The held-out sample's figures (:attr:`ros2course.dev.mutants.RecordedScore.held_out`) in a cell."""
    held = row.held_out
    if held is None:
        earlier = _earlier_held_out(row.data.get(mut.EARLIER_KEY, []), row.data.get("fingerprint"))
        if earlier:  # a first sample measured again drops its held-out one: what the earlier ones scored still shows
            return ("not drawn since the first sample was measured again; earlier held-out samples: "
                    + ", ".join(earlier))
        return "not drawn"
    data = held.data
    if held.spent:  # nothing left to draw: the lesson's every mutant was shown by an earlier sample
        earlier = _earlier_held_out(data.get("earlier", []), data.get("fingerprint"))
        if not earlier and row.data.get("graded") and row.data.get("graded") == row.data.get("pool"):
            return (f"none left to draw: the first sample graded every mutant (seed {data.get('seed', '?')} drew "
                    "0); the lesson has too few mutants for a held-out score")
        return (f"none left to draw: all the mutants the first sample left were shown by earlier held-out samples "
                f"(seed {data.get('seed', '?')} drew 0), so any new figure would be tuned"
                + ("; what they scored: " + ", ".join(earlier) if earlier else
                   "; the lesson has too few mutants for a held-out score"))
    uncovered = len(data.get("survivors", []))
    text = (f"{_pct(held.tuned)} of {held.counted} counted (raw {_pct(held.raw)}; {data['graded']} graded of the "
            f"{data.get('pool', '?')} no earlier sample took, seed {data.get('seed', '?')}"
            f"{', ' + data['family'] + ' mutants' if data.get('family', mut.UNIVERSALMUTATOR) != mut.UNIVERSALMUTATOR else ''}"
            f"; {uncovered} uncovered)")
    if held.too_small:
        text += _too_small(held.counted, data)
    if held.stale and not row.stale:
        text += f" **stale** ({data.get('date', '?')})"
    earlier = _earlier_held_out(data.get("earlier", []), data.get("fingerprint"))
    if earlier:
        text += "; earlier held-out samples: " + ", ".join(earlier)
    pooled = mut.pooled_held_out(row.data, data.get("fingerprint") or "")
    if pooled is not None and pooled.samples > 1 and not held.stale:
        text += (f"; **all {pooled.samples} held-out samples under this grader together: {_pct(pooled.score)} of "
                 f"{pooled.counted} counted** (seeds {', '.join(str(x) for x in pooled.seeds)})")
    return text


def _recorded_row(lesson_id: str, data: dict) -> str:
    """A table row from the lesson's ``mutation-score.json`` (:func:`ros2course.dev.mutants.recorded_score`):
    the raw kill rate beside the tuned score (first sample, after triage) and its counted denominator, the
    held-out sample's score, and whether the row was measured under the lesson's current grader fingerprint."""
    lesson = load_catalog().get(lesson_id)
    row = mut.recorded_score(lesson)
    aside = data.get("set_aside", 0)
    graded = (f"{data['graded']} of {data['generated'] - aside} (seeded sample)" if data.get("sampled")
              else f"{data['graded']} (all)") + (f"; {aside} set aside" if aside else "")
    tuned = _pct(row.tuned)
    if row.too_small:
        tuned += _too_small(row.counted, data)
    when = f"{data.get('date', '?')}, course {data.get('course_version') or '?'}"
    current = f"**stale** ({row.stale.removeprefix('stale: ')})" if row.stale else f"current ({when})"
    by_rule = f" ({data['triaged_by_rule']})" if "triaged_by_rule" in data else ""
    return (f"| {lesson_id} | {data['generated']} | {graded} | {data['killed_by_build']} | {data['killed']} | "
            f"{data['survived']} | {data['triaged']}{by_rule} | "
            f"{data.get('timed_out', 0) + data.get('grader_error', 0)} | "
            f"{_pct(row.raw)} | {row.counted} | {tuned} | {_held_out_cell(row)} | {current} | {steadiness_text(lesson)} |")


#: Kinds of edit :func:`edit_kind` tells apart, in the order the doc lists them.
EDIT_KINDS = ("text wrapped in XX", "None or '' assigned", "a number changed", "another edit")


def edit_kind(original: str, mutated: str) -> str:
    """The kind of a mutant's one-line edit, read from the two lines' text only (never from a verdict), for the
    doc's summary of held-out survivors (:data:`EDIT_KINDS`): mutmut's string mutation (a literal wrapped in
    ``XX``), an assignment's value replaced by ``None`` or ``""``, a number literal changed (the lines equal with
    every number replaced by one symbol), else another edit."""
    before, after = original.strip(), mutated.strip()
    if "XX" in after and "XX" not in before and after.replace("XX", "") == before:
        return EDIT_KINDS[0]
    if before != after and re.search(r"=\s*(None|''|\"\")\s*$", after):
        return EDIT_KINDS[1]
    number = r"(?<![\w.])\d+(\.\d*)?(e-?\d+)?"
    if before != after and re.sub(number, "#", before) == re.sub(number, "#", after):
        return EDIT_KINDS[2]
    return EDIT_KINDS[3]


def _survivor_row(lesson_id: str, where: str, section: str) -> dict | None:
    """A recorded survivor's row (``file:line (key)``, matched by its key) in the lesson's ``mutation-outcomes.json``
    (``section``: ``mutants`` or ``held_out``): ``key``, ``file``, ``line``, ``original``, ``mutant``...; None when
    it is not there (or the file cannot be read)."""
    key = where.rsplit("(", 1)[-1].rstrip(")")
    lesson = load_catalog().get(lesson_id)
    try:
        outcomes = json.loads((lesson.folder / mut.OUTCOMES_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        outcomes = {}
    rows = outcomes.get(section, []) if section == "mutants" else (outcomes.get(section) or {}).get("mutants", [])
    return next((r for r in rows if isinstance(r, dict) and r.get("key") == key), None)


def _survivor_edit(lesson_id: str, where: str, section: str) -> tuple[str, str] | None:
    """The (original, mutated) lines of a recorded survivor (:func:`_survivor_row`); None when it is not there."""
    row = _survivor_row(lesson_id, where, section)
    return None if row is None else (row["original"], row["mutant"])


def _survivor_kinds(lesson_id: str, wheres: list[str]) -> str:
    """``lesson: N survivor(s): 3 text wrapped in XX, 1 another edit`` for a lesson's held-out survivors."""
    counts: dict[str, int] = {}
    for where in wheres:
        edit = _survivor_edit(lesson_id, where, "held_out")
        kind = edit_kind(*edit) if edit is not None else EDIT_KINDS[3]
        counts[kind] = counts.get(kind, 0) + 1
    return (f"- {lesson_id}: {len(wheres)} survivor(s): "
            + ", ".join(f"{counts[k]} {k}" for k in EDIT_KINDS if k in counts))


def _survivor_line(lesson_id: str, where: str, section: str) -> str:
    """``- lesson `key`: file:line: `original` -> `mutated``` for a recorded survivor (``file:line (key)``), the lines
    from the lesson's ``mutation-outcomes.json`` (:func:`_survivor_row`)."""
    row = _survivor_row(lesson_id, where, section)
    if row is None:
        return f"- {lesson_id} (last run): {where}"
    return f"- {lesson_id} `{row['key']}`: {row['file']}:{row['line']}: `{row['original']}` -> `{row['mutant']}`"


def recorded_scores(lesson_ids: list[str]) -> dict[str, dict]:
    """``{lesson id: its mutation-score.json}`` for the lessons that have one (:func:`ros2course.dev.mutants.write_score`)."""
    catalog = load_catalog()
    found = {}
    for lesson_id in lesson_ids:
        path = catalog.get(lesson_id).folder / SCORE_FILE
        try:
            found[lesson_id] = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
    return found


def nothing_to_mutate(lesson_id: str) -> str | None:
    """Why the lesson has no mutant (its reference is commands only, e.g. workspace-setup's ``colcon
    build``), or None when it has files to mutate (:func:`ros2course.dev.mutants.lesson_files`)."""
    lesson = load_catalog().get(lesson_id)
    root = Path(tempfile.mkdtemp(prefix="ros2course-strength-"))
    try:
        if lesson_files(lesson, case_workspace(lesson, "reference", root / "reference")):
            return None
    finally:
        shutil.rmtree(root, ignore_errors=True)
    commands = "; ".join(lesson.reference.commands)
    return "its reference is commands only" + (f" (`{commands}`)" if commands else "") + ": no file to mutate"


def write_doc(path: Path, found: list, not_run: list[str], sample: int, seed: int, jobs: int,
              speedup: str = "") -> None:
    """Write the Markdown report: rows of what ran; rows of the lessons not run this time, from the
    score each lesson's last run recorded (so a run on a few lessons keeps the others'); then the
    lessons never measured. Without ``speedup``, the doc's last parallel speed-up line is kept (it is
    measured only by ``--speedup``)."""
    if not speedup and path.is_file():
        speedup = next((line for line in path.read_text(encoding="utf-8").splitlines()
                        if line.startswith("Parallel speed-up")), "")
    recorded = recorded_scores(not_run)
    # a lesson run now has just written its score file (mutate_lessons): one row format for every lesson
    just_run = recorded_scores([f.lesson for f in found])
    rows_found = [f for f in found if f.lesson not in just_run]
    order = {lesson_id: index for index, lesson_id in enumerate(load_catalog().ids())}  # rows in `list` order
    lines = [
        "# Grader strength: mutation analysis per lesson",
        "",
        f"Generated by `python benchmarks/grader_strength.py --doc-only` from each lesson's recorded run "
        f"(`chapters/<lesson>/mutation-score.json` and `mutation-outcomes.json`, made by `python "
        f"benchmarks/grader_strength.py LESSON` = `ros2course dev mutate --sample {sample} --seed {seed}`, "
        f"with `--held-out 30` for the held-out sample; `--jobs` changes no outcome); tests/test_mutate.py regenerates it and compares. Mutants of each lesson's reference "
        "files come from universalmutator (its Python rules, checked by its own Python handler, for `.py`; "
        "its universal rules for package.xml, scripts and CMake; a package.xml mutant that is no longer XML is "
        "dropped as invalid, as the Python handler drops a `.py` one that does not compile, and a changed comment "
        "line or XML with the same elements as equivalent: `ros2course.dev.mutants.invalid_mutant`, "
        "`equivalent_mutant`); each is graded by the "
        "lesson's grader through the batch engine (`ros2course grade`'s isolation and limits).",
        "",
        "Why universalmutator: one maintained tool (PyPI, regular-expression rules) covers every kind of file "
        "the lessons have (Python, C++, bash scripts, CMake, package.xml, launch files); its Python handler "
        "drops mutants that do not compile or compile to the original's bytecode. Python-only tools (mutmut, "
        "cosmic-ray) would leave the script, CMake and C++ lessons without mutants.",
        "",
        "**Raw** kill rate = killed / (graded - killed by build), before any triage. **Counted** = graded - killed "
        f"by build - triaged. Score after triage = killed / counted; a row with fewer than {mut.MIN_COUNTED} counted "
        "mutants is too small to judge a grader by, and says so. The score after triage is **tuned**: the triage "
        "was written looking at that (first) sample. The **held-out** score is not: a second seeded sample of "
        "mutants that neither the first nor an earlier held-out sample took (`--held-out 30`, another seed: once "
        "its survivors were looked at, a held-out sample is tuned too, so the cell also lists what every earlier "
        "held-out sample of the lesson scored, which a new one never hides), graded afterwards with "
        "`mutation.yaml`'s rules and entries as they were, nothing added; its survivors no rule or entry covers "
        "count against it and are listed below for the author (strengthen the grader, or add a rule that "
        "applies from the next held-out sample on). Where a lesson's universalmutator mutants were all shown by "
        "earlier samples, a held-out sample can come from a second tool, cosmic-ray's core operators on the "
        "lesson's Python files (`--held-out 30 --family cosmic-ray`; the cell says \"cosmic-ray mutants\"), and "
        "where those were all shown too, from a third, mutmut 2's mutations of the Python files (`--family mutmut`: "
        "strings wrapped in XX, assignments of None, numbers off by one, swapped keywords and operators), and "
        "after those, from a fourth, poodle's built-in mutators (`--family poodle`: a call, a subscript or a return "
        "value replaced by None, a decorator removed, an augmented assignment made plain, besides its own operator, "
        "number, keyword and XX string edits), and after those, from a fifth, MutPy's operators (`--family mutpy`, "
        "mutpy-pynguin: `self.x` made `x`, an exception handler's body swallowed or re-raised, a `super()` call "
        "removed, a loop run zero times, once or reversed, a statement made `pass`, a decorator removed or added; "
        "each spliced into the file's text, and one whose syntax tree another tool's mutant has is dropped): "
        "mutants nobody looked at while the rules were written, an edit two tools make counted once. Where more than one held-out sample was graded under the lesson's current grader, the cell also gives **all of them together** (killed / counted over every one): a lesson is judged by that pooled figure, never by the best or the latest sample, since drawing samples until one scores well would narrow the sample to a lucky one. **Fingerprint**: each run records its lesson's "
        "grader fingerprint (`ros2course.grade.fingerprint`: the grader and the course modules it imports, the kit "
        "and grading engine modules they or the engine import, lesson.yaml, the reference files); a row measured under another fingerprint (the "
        "grader, engine or reference changed since) is **stale**, with the date of its run, and `dev validate` "
        "says so too. Triage is a configuration: the raw rate is the figure it cannot change. "
        "Triage lives in `chapters/<lesson>/mutation.yaml` (whose `files:` may also narrow the files mutated; "
        "default: the files the lesson's own starter gives with TODOs or does not give): first **rules**, kinds "
        "of survivor decided before they are tested and applied mechanically (a docstring replaced by `pass`, "
        "the `if __name__ == '__main__':` block of a console_scripts node, package.xml free text), each with a "
        "reason (a rule many lessons share is written once, in `chapters/mutation-rules.yaml`, and a lesson takes "
        "it as it is with `- use: <id>`); a rule may never cover a line that implements a requirement of the "
        "lesson's `contract.yaml` "
        "(`ros2course.dev.mutants.rule_conflicts`); then per-mutant **entries** for what no rule covers, each "
        "naming one mutant by its identity (its key), never by line text alone. `triaged (by rule)` counts both, "
        "and in brackets those a rule covers. A rule marked `set_aside` (free text no program reads) takes its "
        "mutants out before sampling, never graded, so the sample is spent on mutants that count. Survivors' "
        "diffs are in the run's `survivors/` folder.",
        "",
        "Reference steadiness: the lesson's reference graded N times, K at once (two learners' checks on one "
        "machine), by `python benchmarks/grader_strength.py LESSON... --repeat N --load K` (recorded in "
        "`chapters/<lesson>/steadiness.json`): steady when no check changed its verdict.",
        "",
        "| lesson | mutants generated | graded | killed by build | killed | survived | triaged (by rule) | "
        "timed out / grader error | raw kill rate | counted | tuned score (first sample, after triage) | "
        "held-out score | measured under the current grader? | reference steadiness (`dev validate --repeat`) |",
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---|---|",
        *[row for _, row in sorted([(order.get(f.lesson, 0), _row(f, sample)) for f in rows_found]
                                   + [(order.get(lesson_id, 0), _recorded_row(lesson_id, data))
                                      for lesson_id, data in {**recorded, **just_run}.items()])],
        "",
    ]
    records = {**recorded, **just_run}
    ranked = sorted(records, key=lambda lesson_id: order.get(lesson_id, 0))
    survivors = [f"- {f.lesson} `{g.mutant.key}`: {g.mutant.file}:{g.mutant.line}: "
                 f"`{g.mutant.original.strip()}` -> `{g.mutant.mutated.strip()}`"
                 for f in rows_found for g in f.graded if g.outcome == "survived" and not g.triaged]
    survivors += [_survivor_line(lesson_id, where, "mutants") for lesson_id in ranked
                  for where in records[lesson_id].get("survivors", [])]
    held = [_survivor_line(lesson_id, where, "held_out") for lesson_id in ranked
            for where in (records[lesson_id].get("held_out") or {}).get("survivors", [])]
    if held:
        lines += ["## Held-out survivors no rule covers", "",
                  "Each counts against its lesson's held-out score: a change the grader did not notice, in a sample "
                  "the triage was not written for. For the author: strengthen the grader, or add a rule (it applies "
                  "from the next held-out sample on).", ""]
        lines += held
        lines += ["", "By kind of edit, read from each edit's text alone (a summary for the reader: every one of them "
                  "still counts against its lesson):", ""]
        lines += [_survivor_kinds(lesson_id, wheres) for lesson_id in ranked
                  if (wheres := (records[lesson_id].get("held_out") or {}).get("survivors", []))]
        lines.append("")
    if survivors:
        lines += ["## Survivors not triaged", "",
                  "Each is a change the grader did not notice: a gap to close in the grader, or a mutant to triage "
                  "in the lesson's mutation.yaml with a reason.", ""]
        lines += survivors
        lines.append("")
    if speedup:
        lines += [speedup, ""]
    never = [lesson_id for lesson_id in not_run if lesson_id not in recorded]
    unmutable = {lesson_id: why for lesson_id in never if (why := nothing_to_mutate(lesson_id))}
    if unmutable:
        lines += ["Nothing to mutate: " + "; ".join(f"{lesson_id}, {why}" for lesson_id, why in unmutable.items())
                  + ".", ""]
    never = [lesson_id for lesson_id in never if lesson_id not in unmutable]
    if never:
        lines += ["Never measured (no `mutation-score.json`; the table has no row for them): "
                  + ", ".join(never) + ".", ""]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines), encoding="utf-8")


def _recorded_run(lesson) -> dict | None:
    """The lesson's first sample as its committed records have it (``mutation-outcomes.json``'s mutants and
    ``mutation-score.json``'s counts), in ``mutation.json``'s row shape; None when either is missing. So a
    re-triage needs no run folder: the per-mutant outcomes committed with the lesson are enough (issue 37)."""
    score = mut.read_json_object(lesson.folder / mut.SCORE_FILE)
    outcomes = mut.read_json_object(lesson.folder / mut.OUTCOMES_FILE)
    if not score or not isinstance(outcomes.get("mutants"), list):
        return None
    texts = {rel: text.splitlines() for rel, text in mut.reference_texts(lesson).items()}
    mutants = []
    for m in outcomes["mutants"]:
        if not isinstance(m, dict):
            continue
        # the record keeps lines stripped; a rule reads indentation (a block, `^\s`): the reference has it
        lines, number = texts.get(m.get("file", ""), []), m.get("line", 0)
        full = lines[number - 1] if 1 <= number <= len(lines) else ""
        if m.get("original") and full.strip() == m["original"].strip():
            indent = full[:len(full) - len(full.lstrip())]
            m = {**m, "original": full, "mutant": indent + m["mutant"].lstrip() if m.get("mutant") else m.get("mutant", "")}
        mutants.append({**m, "lost": m.get("lost", [])})
    return {"mutants": mutants, "generated": score.get("generated", 0), "sampled": bool(score.get("sampled", score.get("sample"))),
            "seconds": score.get("seconds", 0.0), "set_aside": score.get("set_aside", 0),
            "sample": score.get("sample"), "seed": score.get("seed", 1), "pool": score.get("pool", 0)}


def retriage(lesson_ids: list[str], out: Path) -> list:
    """Apply each lesson's ``mutation.yaml`` as it is now to the outcomes of its recorded first sample (the
    lesson's committed ``mutation-outcomes.json``, else its last run in ``OUT/mutation.json``), grading nothing,
    and record the score
    (``mutation-score.json``): a survivor triaged after its run.

    The outcomes are that run's; only which survivors are triaged changes (rules, then entries by identity).
    The held-out sample stays as it was graded and triaged: it is never re-triaged. A lesson the file does not
    have is skipped.
    """
    try:
        rows = json.loads((out / "mutation.json").read_text(encoding="utf-8")).get("lessons", {})
    except (OSError, ValueError):
        rows = {}
    catalog, found = load_catalog(), []
    for lesson_id in lesson_ids:
        lesson = catalog.get(lesson_id)
        # the committed per-mutant outcomes are the record; a run folder may hold an older run of the lesson
        row = _recorded_run(lesson) or rows.get(lesson_id)
        if row is None:
            continue
        graded = [mut.Graded(mut.Mutant(m["file"], m["line"], m["original"], m["mutant"], ""), m["outcome"],
                             list(m["lost"]), m.get("score", 0.0), m.get("max_score", 0.0), m.get("message", ""),
                             cached=True) for m in row["mutants"]]
        config = mut.load_config(lesson)
        mut.apply_triage(graded, config, [], originals=mut.reference_texts(lesson, config=config))
        found.append(mut.LessonMutation(lesson_id, row["generated"], graded, [], row["sampled"],
                                        row.get("seconds", 0.0), set_aside=row.get("set_aside", 0),
                                        sample=row.get("sample"), seed=row.get("seed", 1), pool=row.get("pool", 0)))
        before = mut.recorded_score(lesson)
        # the outcomes are that run's: its date and fingerprint stay (none recorded: stale, as it should read)
        mut.write_score(lesson, found[-1], measured={"date": before.data.get("date", "?"),
                                                     "fingerprint": before.data.get("fingerprint", ""),
                                                     "course_version": before.data.get("course_version", ""),
                                                     **mut.course_part(before.data)}
                        if before is not None else {"date": "?", "fingerprint": ""}, keep_held_out=True)
    return found


def update_readme(readme: Path = ROOT / "README.md") -> None:
    """Rewrite the README's lesson table (:func:`ros2course.dev.validate.with_lessons_table`)."""
    readme.write_text(with_lessons_table(readme.read_text(encoding="utf-8")), encoding="utf-8")


def record_steadiness(lesson_ids: list[str], repeat: int, load: int, doc: Path, sample: int = 30, seed: int = 1,
                      jobs: int = 2) -> int:
    """Grade each lesson's reference ``repeat`` times, ``load`` at once (``dev validate --repeat``), record
    each in its ``steadiness.json``, then rewrite the doc and the README's table from the records."""
    catalog = load_catalog()
    console = Console(stderr=True)
    rows = repeat_lessons(lesson_ids, repeat, load, ["reference"], progress=console)
    for row in rows:
        write_steadiness(catalog.get(row.lesson), row)
    render_steadiness(rows, console)
    write_doc(doc, [], catalog.ids(), sample, seed, jobs)  # the mutation rows as recorded: the doc's header stays true
    update_readme()
    return 0 if all(r.ok for r in rows) else 1


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("lessons", nargs="*", help="lesson ids (default: every lesson)")
    parser.add_argument("--sample", type=int, default=30)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=ROOT / ".mutation-out")
    parser.add_argument("--doc", type=Path, default=ROOT / "docs" / "grader-strength.md")
    parser.add_argument("--speedup", action="store_true", help="also time --jobs 1 against --jobs N, uncached")
    parser.add_argument("--repeat", type=int, default=0, metavar="N",
                        help="instead of mutants: grade each lesson's reference N times (--load at once) and record "
                             "its steadiness (chapters/<lesson>/steadiness.json)")
    parser.add_argument("--load", type=int, default=2, metavar="K", help="with --repeat: gradings at once")
    parser.add_argument("--retriage", action="store_true",
                        help="grade nothing: apply each lesson's mutation.yaml as it is now to its last run's outcomes "
                             "(--out's mutation.json) and rewrite the scores, the doc and README's table")
    parser.add_argument("--doc-only", action="store_true",
                        help="grade nothing: rewrite the doc and README's lesson table from the recorded runs "
                             "(what tests/test_mutate.py compares with the committed doc)")
    parser.add_argument("--held-out", type=int, default=None, metavar="N",
                        help="grade each lesson's held-out sample of N mutants (disjoint from its recorded first "
                             "sample and earlier held-out ones, another seed), triaged with mutation.yaml as it is, and record it beside the first")
    parser.add_argument("--first-loss", action="store_true",
                        help="stop grading each mutant at its first lost point (dev mutate --first-loss): the same "
                             "outcomes, sooner")
    parser.add_argument("--held-out-seed", type=int, default=None, metavar="S",
                        help="with --held-out: its seed (default: --seed + 1)")
    parser.add_argument("--family", default="universalmutator", metavar="TOOL",
                        help="with --held-out: the tool whose mutants it draws, universalmutator, cosmic-ray (its "
                             "core operators on the Python files: fresh mutants for a lesson whose universalmutator "
                             "pool earlier samples spent), mutmut (mutmut 2's mutations of the Python files), poodle "
                             "(poodle's built-in mutators on the Python files) or mutpy (MutPy's operators, spliced "
                             "into the Python files; a mutant another tool makes in other words is dropped)")
    parser.add_argument("--readme", action="store_true",
                        help="only rewrite README.md's lesson table from the scores the lessons recorded (no mutants graded)")
    args = parser.parse_args()
    if args.readme:
        update_readme()
        return 0
    if args.doc_only:
        write_doc(args.doc, [], load_catalog().ids(), args.sample, args.seed, args.jobs)
        update_readme()
        return 0
    env_mod.activate_process()
    if args.repeat:
        return record_steadiness(args.lessons or load_catalog().ids(), args.repeat, args.load, args.doc,
                                 args.sample, args.seed, args.jobs)
    every = load_catalog().ids()
    chosen = args.lessons or every
    console = Console(stderr=True)
    if args.retriage:
        found = retriage(chosen, args.out)
        render(found, console, diffs=False)
        write_doc(args.doc, found, [i for i in every if i not in chosen], args.sample, args.seed, args.jobs)
        update_readme()
        return 0
    begin = time.monotonic()
    chosen = [lesson_id for lesson_id in chosen if not nothing_to_mutate(lesson_id)]  # listed as such in the doc
    found = mutate_lessons(chosen, args.out, sample=args.sample, seed=args.seed, jobs=args.jobs,
                           console=console, held_out=args.held_out,
                           held_out_seed=args.held_out_seed, first_loss=args.first_loss,
                           family=args.family) if chosen else []
    render(found, console, diffs=False)
    speedup_file = args.out / "speedup.txt"
    speedup = speedup_file.read_text(encoding="utf-8").strip() if speedup_file.is_file() else ""
    if args.speedup:
        walls = {}
        for jobs in (1, args.jobs):
            scratch = Path(tempfile.mkdtemp(prefix="ros2course-strength-"))
            try:
                t0 = time.monotonic()
                mutate_lessons(chosen[:1], scratch, sample=args.sample, seed=args.seed, jobs=jobs, console=None)
                walls[jobs] = time.monotonic() - t0
            finally:
                shutil.rmtree(scratch, ignore_errors=True)
        speedup = (f"Parallel speed-up ({chosen[0]}, {args.sample} mutants, uncached): --jobs 1 {walls[1]:.0f} s, "
                   f"--jobs {args.jobs} {walls[args.jobs]:.0f} s, x{walls[1] / walls[args.jobs]:.2f}.")
        console.print(speedup)
        speedup_file.write_text(speedup + "\n", encoding="utf-8")
    write_doc(args.doc, found, [i for i in every if i not in chosen], args.sample, args.seed, args.jobs, speedup)
    update_readme()
    console.print(f"wrote {args.doc} and README.md's lesson table ({time.monotonic() - begin:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
