"""``ros2course dev mutate``: each mutant of a lesson's reference graded as a class through the batch engine.

Mutants come from :mod:`ros2course.dev.mutants` (universalmutator). Each is laid
out as one submission (the reference workspace, one file replaced) in a scratch
submissions folder and graded by :func:`ros2course.batch.runner.run_batch`: the
same isolation, limits, parallelism and resume as a class, so a mutant that
hangs, forks or floods its output is held like a hostile submission.

``OUT`` keeps:

* ``mutation-cache.json``: outcome per (grader source, course content, mutant
  content) hash: a second run grades only mutants it has not seen;
* ``batch/<lesson>-<hash>/``: the batch's own output (``results.jsonl``); a run
  stopped by Ctrl+C resumes from it;
* ``mutation.json``: every lesson's counts, score and mutants (``lessons``: the first sample;
  ``held_out``: the held-out samples, :func:`ros2course.dev.mutants.held_out_sample`);
* ``survivors/<lesson>/<key>.diff``: each survivor's unified diff.
"""

from __future__ import annotations

import json
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table
from ros2course.dev import first_line
from ros2course.dev.parity import case_workspace
from ros2course.batch.runner import run_batch
from ros2course.errors import CourseError
from ros2course.grade.checklist import StopWhen
from ros2course.files import atomic_write_text
from ros2course.dev import mutants as mut
from ros2course.lesson.catalog import Lesson, load_catalog
from ros2course.report.gradebook import read_results

CACHE_FILE = "mutation-cache.json"
RESULT_FILE = "mutation.json"
#: Outcomes that say nothing lasting about a mutant: never cached, and their batch rows are graded again.
UNFINISHED = (mut.GRADER_ERROR, mut.TIMED_OUT)


def _forget_unfinished(results_path: Path) -> int:
    """Drop the rows of ``results_path`` (a mutation batch's ``results.jsonl``) whose outcome is in
    :data:`UNFINISHED`, so that resuming the batch grades those mutants again; returns how many.

    Without it a resumed batch would keep a grader error or a timeout of an earlier run forever.
    """
    records = read_results(results_path)
    kept = [r for r in records if mut.classify(r)[0] not in UNFINISHED]
    if len(kept) == len(records):
        return 0
    atomic_write_text(results_path, "".join(json.dumps(r.to_record(), separators=(",", ":"), ensure_ascii=False)
                                            + "\n" for r in kept))
    return len(records) - len(kept)


def _student(mutant: mut.Mutant) -> str:
    return f"{Path(mutant.file).stem[:24]}.{mutant.key}"


def mutate_lesson(lesson: Lesson, out: Path, sample: int | None = None, seed: int = 1, jobs: int = 1,
                  timeout: float = 300.0, console: Console | None = None, held_out: int | None = None,
                  held_out_seed: int | None = None, first_loss: bool = False,
                  family: str = mut.UNIVERSALMUTATOR) -> mut.LessonMutation:
    """Generate, grade (what the cache does not know) and classify one lesson's mutants.

    Args:
        lesson: the lesson.
        out: the output folder (cache, batch outputs, survivors' diffs).
        sample: grade only this many mutants, picked with ``seed`` (None: all).
        seed: the sample's random seed.
        jobs: mutants graded at once.
        timeout: wall-clock seconds per mutant (the batch's per-submission limit).
        console: progress and the batch's progress bar (None: quiet).
        held_out: instead of the first sample, grade a held-out one of this many mutants
            (:func:`ros2course.dev.mutants.held_out_sample`): drawn with ``held_out_seed`` (default
            ``seed + 1``) from the mutants neither the first sample (``sample``, ``seed``) nor the lesson's
            recorded first run nor a held-out sample recorded before took, triaged with ``mutation.yaml`` as it is.
        family: where the held-out sample's mutants come from (:data:`ros2course.dev.mutants.FAMILIES`); the
            first sample is always universalmutator's.
        first_loss: each mutant's grading stops at its first lost point
            (:class:`~ros2course.grade.checklist.StopWhen` ``any_loss``): the same outcome (a mutant is killed when
            any check loses points), sooner; its ``lost`` checks are then those lost before the stop.

    Raises:
        MissingRequirement: universalmutator (or ``family``'s tool), or what the lesson requires, is not installed.
        LessonFormatError: a malformed ``mutation.yaml``.
        CourseError: no file to mutate; the batch refuses the lesson.
    """
    begin = time.monotonic()
    config = mut.load_config(lesson)
    root = Path(tempfile.mkdtemp(prefix=f"ros2course-mutate-{lesson.id}-"))
    root.chmod(0o755)
    try:
        reference = case_workspace(lesson, "reference", root / "reference")
        every = mut.generate_mutants(lesson, reference, config)
        candidates, aside = mut.set_aside(every, config)
        picked = mut.sample_mutants(candidates, sample, seed)
        pool = len(candidates)
        generated = len(every)
        if held_out is not None:
            # neither the first sample nor a held-out sample recorded before (its survivors were looked at)
            recorded = mut.recorded_first_sample(lesson) | mut.recorded_held_out(lesson)
            first = picked
            if family != mut.UNIVERSALMUTATOR:  # another tool's mutants; an edit both make has one key
                others = mut.generate_mutants(lesson, reference, config, family)
                if family == mut.MUTPY:  # its spliced edits are in ast.unparse's style: compared by syntax tree
                    made = [*every, *(m for other in (mut.COSMIC_RAY, mut.MUTMUT, mut.POODLE)
                                      for m in mut.generate_mutants(lesson, reference, config, other))]
                    others = mut.drop_made_by_others(others, made)
                candidates, aside = mut.set_aside(others, config)
                generated, every = len(others), [*every, *others]
            picked = mut.held_out_sample(candidates, first, held_out,
                                         seed + 1 if held_out_seed is None else held_out_seed, recorded)
            taken = {m.key for m in first} | recorded
            pool = sum(m.key not in taken for m in candidates)
        grader, course = mut.grader_hash(lesson), mut.course_hash(reference, lesson)
        cache_path = out / CACHE_FILE
        cache = mut.read_json_object(cache_path)
        todo = [m for m in picked if mut.cache_key(grader, course, m) not in cache]
        this_run: dict[str, dict[str, Any]] = {}  # outcomes of this run that are never cached (UNFINISHED)
        graded_now: dict[str, dict[str, Any]] = {}  # outcomes of this run that are cached
        if console is not None:
            console.print(f"{lesson.id}: {generated} mutants generated"
                          + (f" by {family}" if family != mut.UNIVERSALMUTATOR else "")
                          + (f" ({len(aside)} of rules marked set_aside, set aside)" if aside else "")
                          + f", {len(picked)} picked"
                          + (f" for the held-out sample, from the {pool} no recorded sample took"
                             if held_out is not None else
                             f"{f' (--sample {sample} --seed {seed})' if len(picked) < len(candidates) else ''}")
                          + ", "
                          f"{len(picked) - len(todo)} known from the cache, {len(todo)} to grade")
        if todo:
            submissions = root / "submissions"
            submissions.mkdir()
            for mutant in todo:
                dest = submissions / _student(mutant)
                shutil.copytree(reference, dest, symlinks=True)
                (dest / mutant.file).write_text(mutant.content, encoding="utf-8")
            batch_out = out / "batch" / f"{lesson.id}-{course[:8]}{grader[:8]}"
            _forget_unfinished(batch_out / "results.jsonl")
            stop = {_student(m): StopWhen(any_loss=True) for m in todo} if first_loss else None
            report = run_batch(submissions, [lesson.id], batch_out, jobs=jobs, timeout=timeout,
                               resume=batch_out.exists(), console=console, stop_when=stop)
            results = {r.student: r for r in report.records if r.lesson == lesson.id}
            for mutant in todo:
                result = results.get(_student(mutant))
                if result is None:
                    continue  # interrupted before this one: graded next time
                outcome, lost = mut.classify(result)
                row = {"outcome": outcome, "lost": lost, "score": result.score, "max_score": result.max_score,
                       "message": first_line(result.message)}
                # a grader error or a timeout says something about this run (a loaded machine, a grader
                # bug since fixed), not about the mutant: reported now, graded again next time
                (this_run if outcome in UNFINISHED else graded_now)[mut.cache_key(grader, course, mutant)] = row
            out.mkdir(parents=True, exist_ok=True)
            # merged into the file as it is now: another run on the same --out (another lesson) may have
            # written it since this one read it
            cache.update(graded_now)
            atomic_write_text(cache_path, json.dumps({**mut.read_json_object(cache_path), **graded_now}, indent=1,
                                                     sort_keys=True) + "\n")
        graded = []
        fresh = {m.key for m in todo}
        for mutant in picked:
            key = mut.cache_key(grader, course, mutant)
            known = cache.get(key) or this_run.get(key)
            if known is None:
                continue
            graded.append(mut.Graded(mutant, known["outcome"], list(known["lost"]), known.get("score", 0.0),
                                     known.get("max_score", 0.0), known.get("message", ""),
                                     cached=mutant.key not in fresh))
        stale = mut.apply_triage(graded, config, every)
        originals = {m.file: (reference / m.file).read_text(encoding="utf-8") for m in picked}
        diffs = {g.mutant.key: g.mutant.diff(originals[g.mutant.file])
                 for g in graded if g.outcome == mut.SURVIVED and not g.triaged}
        folder = out / "survivors" / (lesson.id + ("-held-out" if held_out is not None else ""))
        shutil.rmtree(folder, ignore_errors=True)
        for key, diff in diffs.items():
            folder.mkdir(parents=True, exist_ok=True)
            (folder / f"{key}.diff").write_text(diff, encoding="utf-8")
        return mut.LessonMutation(lesson.id, generated, graded, stale, len(picked) < len(candidates),
                                  time.monotonic() - begin, diffs, set_aside=len(aside), sample=sample,
                                  seed=seed if held_out is None else (seed + 1 if held_out_seed is None
                                                                      else held_out_seed),
                                  held_out=held_out is not None, pool=pool, family=family)
    finally:
        shutil.rmtree(root, ignore_errors=True)


def mutate_lessons(lesson_ids: list[str], out: Path, sample: int | None = None, seed: int = 1, jobs: int = 1,
                   timeout: float = 300.0, console: Console | None = None, held_out: int | None = None,
                   held_out_seed: int | None = None, first_loss: bool = False,
                   family: str = mut.UNIVERSALMUTATOR) -> list[mut.LessonMutation]:
    """:func:`mutate_lesson` for each lesson, then ``OUT/mutation.json`` (written even when one lesson fails).

    With ``held_out``, each lesson's held-out sample instead of its first one (:func:`mutate_lesson`), recorded
    beside the first (:func:`ros2course.dev.mutants.write_held_out`); the lesson must have a recorded first run.

    Raises:
        UnknownLesson: a lesson id is not in the catalog (before anything is graded).
        CourseError: bad numbers; a held-out sample of a lesson with no recorded first run; see :func:`mutate_lesson`.
    """
    if not lesson_ids:
        raise CourseError("no lesson given", "e.g. ros2course dev mutate print-forever-node --sample 5")
    if jobs < 1:
        raise CourseError(f"--jobs must be at least 1 (got {jobs})", "e.g. --jobs 2")
    if sample is not None and sample < 1:
        raise CourseError(f"--sample must be at least 1 (got {sample})", "e.g. --sample 30")
    if held_out is not None and held_out < 1:
        raise CourseError(f"--held-out must be at least 1 (got {held_out})", "e.g. --held-out 30")
    mut.require_tool()  # every family's sample is drawn apart from universalmutator's mutants (their keys)
    mut.require_tool(family)
    if family != mut.UNIVERSALMUTATOR and held_out is None:
        raise CourseError(f"the first sample is universalmutator's: --family {family} draws a held-out sample",
                          f"add --held-out 30 (after the first sample: ros2course dev mutate {' '.join(lesson_ids)} "
                          "--sample 30)")
    catalog = load_catalog()
    lessons = [catalog.get(i) for i in lesson_ids]
    if held_out is not None:
        missing = [lesson.id for lesson in lessons if not mut.recorded_first_sample(lesson)]
        if missing:
            raise CourseError(f"no recorded first sample for {', '.join(missing)}: a held-out sample is drawn after it",
                              f"grade the first sample first: ros2course dev mutate {' '.join(missing)} "
                              f"--sample {sample or 30} --seed {seed}")
    out = out.absolute()
    out.mkdir(parents=True, exist_ok=True)
    found: list[mut.LessonMutation] = []
    try:
        for lesson in lessons:
            found.append(mutate_lesson(lesson, out, sample, seed, jobs, timeout, console, held_out, held_out_seed,
                                       first_loss, family))
            mut.write_score(lesson, found[-1])
    finally:
        before = mut.read_json_object(out / RESULT_FILE)
        section = "held_out" if held_out is not None else "lessons"
        previous = {name: before.get(name, {}) if isinstance(before.get(name, {}), dict) else {}
                    for name in ("lessons", "held_out")}
        previous[section] = {**previous[section], **{f.lesson: f.to_dict() for f in found}}
        atomic_write_text(out / RESULT_FILE, json.dumps({"seed": seed, "sample": sample, **previous},
                                                        indent=2) + "\n")
    return found


def render(found: list[mut.LessonMutation], console: Console, diffs: bool = True) -> None:
    """The summary table, each survivor's diff, the triaged ones and the stale triage entries."""
    if not console.is_terminal:
        console.width = max(console.width, 150)  # a file or pipe: one row per lesson, whatever COLUMNS says
    table = Table(title="ros2course dev mutate", title_justify="left")
    table.add_column("lesson", no_wrap=True)
    for column in ("mutants", "graded", "killed", "build", "survived", "triaged", "t/o+err", "score", "s"):
        table.add_column(column, justify="right", no_wrap=True)
    for f in found:
        score = "n/a" if f.score is None else f"{100 * f.score:.0f}%"
        table.add_row(f.lesson + (" (held-out)" if f.held_out else ""), f"{f.generated}" + (f" (-{f.set_aside})" if f.set_aside else ""),
                      f"{len(f.graded)}{'*' if f.sampled else ''}",
                      str(f.count(mut.KILLED)), str(f.count(mut.KILLED_BY_BUILD)), str(f.count(mut.SURVIVED)),
                      str(f.triaged), f"{f.count(mut.TIMED_OUT)}+{f.count(mut.GRADER_ERROR)}", score,
                      f"{f.seconds:.0f}")
    console.print(table)
    console.print("build: killed by the build (no check ran); *: a seeded sample; (-N): mutants of the rules "
                  "marked set_aside, never graded; score: killed / (graded - build - triaged); held-out: a second "
                  "sample disjoint from the first, triaged with mutation.yaml as it is")
    for f in found:
        killers: dict[str, int] = {}
        for g in f.graded:
            if g.outcome == mut.KILLED:
                for check in g.lost:
                    killers[check] = killers.get(check, 0) + 1
        if killers:
            console.print(f"{f.lesson}: checks that killed mutants: "
                          + ", ".join(f"{c} ({n})" for c, n in sorted(killers.items(), key=lambda x: -x[1])))
        for g in f.graded:
            if g.outcome in (mut.TIMED_OUT, mut.GRADER_ERROR):
                console.print(f"{f.lesson}: {g.outcome}: {g.mutant.file}:{g.mutant.line} ({g.mutant.key}): "
                              f"{g.message}", markup=False)
        if diffs:
            for key, diff in f.diffs.items():
                console.print(f"[yellow]survived[/] {f.lesson} {key}:")
                console.print(diff.rstrip("\n"), markup=False, highlight=False, soft_wrap=True)
        for hit in f.rules_on_killed():
            console.print(f"{f.lesson}: a rule matches a killed mutant (is its kind equivalent?): {hit}", markup=False)
        for entry in f.stale:
            what = f"rule {entry.id}" if isinstance(entry, mut.Rule) else f"entry {entry.describe()}"
            console.print(f"[yellow]stale[/] {f.lesson}: mutation.yaml {what} matches no mutant")


def as_dicts(found: list[mut.LessonMutation]) -> list[dict[str, Any]]:
    """Each lesson's :meth:`~ros2course.dev.mutants.LessonMutation.to_dict`."""
    return [f.to_dict() for f in found]
