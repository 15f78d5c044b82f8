"""Contract coverage (issue 37): every lesson's ``contract.yaml`` loads cleanly, and docs/contract-coverage.md is current.

No ROS: a grader module loads for its ``CHECKS`` alone. The loader's problems are
``path:line: message``; each kind is shown on a small bad file.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from ros2course.dev.coverage import COVERAGE_DOC, coverage_document, lesson_coverage
from ros2course.lesson.catalog import content_root, load_catalog
from ros2course.lesson.contract import CONTRACT_FILE, load_contract

CATALOG = load_catalog()
TRACED = [lesson.id for lesson in CATALOG.lessons if (lesson.folder / CONTRACT_FILE).is_file()]


@pytest.mark.parametrize("lesson_id", TRACED)
def test_a_lesson_s_contract_loads_without_problems(lesson_id: str) -> None:
    row = lesson_coverage(CATALOG.get(lesson_id))
    assert not row.problems, "\n".join(map(str, row.problems))
    assert row.contract is not None and row.contract.requirements


def test_every_lesson_has_a_contract() -> None:
    missing = [lesson.folder.name for lesson in CATALOG.lessons if not (lesson.folder / CONTRACT_FILE).is_file()]
    assert not missing, f"no {CONTRACT_FILE} in: {', '.join(missing)}"


def test_the_committed_coverage_document_is_current() -> None:
    text, _ = coverage_document()  # each contract's problems: test_a_lesson_s_contract_loads_without_problems
    committed = (content_root() / COVERAGE_DOC).read_text(encoding="utf-8")
    assert committed == text, "run `ros2course dev contract-coverage --write`"


GOOD = """\
    lesson: demo
    requirements:
      - id: topic-name
        says: "it publishes /chatter"
        from: instructions
        checks: [topic]
      - id: depth
        says: "with depth 10"
        from: contract
        not_graded: "the graph carries no remote history depth"
"""


def _load(tmp_path: Path, text: str, lesson: str = "demo", checks=("topic", "rate")):
    path = tmp_path / CONTRACT_FILE
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path, *load_contract(path, lesson, set(checks))


def test_a_good_contract_loads(tmp_path: Path) -> None:
    _, contract, problems = _load(tmp_path, GOOD)
    assert not problems
    assert contract is not None and [r.id for r in contract.mapped] == ["topic-name"]
    assert [r.id for r in contract.not_graded] == ["depth"] and contract.requirements[0].source == "instructions"


def _one(problems, path: Path, line: int, *words: str) -> None:
    assert len(problems) == 1, problems
    text = str(problems[0])
    assert text.startswith(f"{path}:{line}: "), text
    for word in words:
        assert word in text, text


def test_a_requirement_with_neither_checks_nor_not_graded(tmp_path: Path) -> None:
    path, contract, problems = _load(tmp_path, GOOD.replace("        checks: [topic]\n", ""))
    assert contract is None
    _one(problems, path, 3, "requirements.0", "checks", "not_graded")


def test_a_requirement_with_both(tmp_path: Path) -> None:
    path, _, problems = _load(tmp_path, GOOD.replace("        checks: [topic]\n",
                                                     "        checks: [topic]\n        not_graded: \"because it is so\"\n"))
    _one(problems, path, 3, "requirements.0", "not both")


def test_an_empty_checks_list(tmp_path: Path) -> None:
    path, _, problems = _load(tmp_path, GOOD.replace("checks: [topic]", "checks: []"))
    _one(problems, path, 3, "empty")


def test_a_check_the_grader_does_not_declare(tmp_path: Path) -> None:
    path, contract, problems = _load(tmp_path, GOOD.replace("checks: [topic]", "checks: [topic,\n          spins]"))
    assert contract is None
    _one(problems, path, 7, "'spins'", "not a check")


def test_a_duplicate_requirement_id(tmp_path: Path) -> None:
    path, _, problems = _load(tmp_path, GOOD.replace("id: depth", "id: topic-name"))
    _one(problems, path, 7, "duplicate", "topic-name", "line 3")


def test_an_unknown_key(tmp_path: Path) -> None:
    path, _, problems = _load(tmp_path, GOOD.replace("        from: contract\n", "        from: contract\n        points: 2\n"))
    _one(problems, path, 10, "unknown key `points`")
    path, _, problems = _load(tmp_path, GOOD + "    owner: h1\n")
    _one(problems, path, 11, "unknown key `owner`")


def test_a_lesson_that_is_not_the_folder_s(tmp_path: Path) -> None:
    path, _, problems = _load(tmp_path, GOOD, lesson="qos")
    _one(problems, path, 1, "'demo'", "'qos'")


def test_a_bad_source_and_bad_yaml(tmp_path: Path) -> None:
    path, _, problems = _load(tmp_path, GOOD.replace("from: contract", "from: readme"))
    _one(problems, path, 9, "requirements.1.from")
    path, _, problems = _load(tmp_path, GOOD.replace('says: "with depth 10"', 'says: "with depth 10'))
    assert problems and str(problems[0]).startswith(f"{path}:") and "not valid YAML" in str(problems[0])


def test_which_reference_lines_implement_a_requirement() -> None:
    """The lines a mutation rule may never cover (issue 37): the code-like terms of what a requirement says, each
    found whole in a line, or the lines its `code:` names; comment and docstring lines implement nothing."""
    from ros2course.lesson.contract import Requirement, implements, says_terms

    assert says_terms("the node is named print_forever (super().__init__('print_forever'))") == \
        ["print_forever", "super().__init__('print_forever')"]
    assert says_terms("main() calls rclpy.init(), creates the node and spins it (rclpy.spin)") == \
        ["main()", "rclpy.init()", "rclpy.spin"]
    assert says_terms("it logs twice a second: a timer with period 0.5 s") == ["0.5"]
    said = Requirement.model_validate({"id": "main-spins", "says": "main() calls rclpy.init() and spins (rclpy.spin)",
                                       "from": "instructions", "checks": ["spins"]})
    node = "src/p/p/node.py"
    assert implements(said, node, "        rclpy.init(args=args)") == "names `rclpy.init()`"  # a call, with arguments
    assert implements(said, node, "    main()") == "names `main()`"
    assert implements(said, node, "            rclpy.spin_once(node)") is None  # a whole term: spin is not spin_once
    assert implements(said, node, '    """main() spins with rclpy.spin."""') is None  # a docstring
    assert implements(said, node, "    # rclpy.spin(node) blocks") is None  # a comment
    rate = Requirement.model_validate({"id": "rate", "says": "a timer with period 0.1 s", "from": "contract",
                                       "checks": ["rate"]})
    assert implements(rate, "src/p/package.xml", "  <version>0.0.1</version>") is None
    named = Requirement.model_validate({**said.model_dump(by_alias=True, exclude_none=True),
                                        "code": [{"file": "src/*/node.py", "line": r"^def main\(|rclpy\.(init|spin)\("}]})
    assert implements(named, node, "    main()") is None  # the call under `if __name__ == '__main__':`
    assert implements(named, node, "def main(args=None):") == r"code: src/*/node.py /^def main\(|rclpy\.(init|spin)\(/"
    assert implements(named, "src/p/other.py", "def main(args=None):") is None
    with pytest.raises(ValueError, match="not a regular expression"):
        Requirement.model_validate({**said.model_dump(by_alias=True, exclude_none=True),
                                    "code": [{"file": "*", "line": "("}]})


def test_a_docstring_implements_a_requirement_only_when_code_marks_it() -> None:
    """A docstring line implements nothing by its words (a rule may triage its mutants), unless a marker of
    the requirement's ``code:`` with ``docstrings: true`` marks it: a lesson that asks for docstrings (python-minimalist-package's
    type-hints-docstrings) keeps a docstring rule off those lines (rule_conflicts)."""
    from ros2course.lesson.contract import Requirement, implements

    line = '        """Return the sum of the public and the private attribute."""'
    derived = Requirement.model_validate({"id": "sum", "says": "method() returns the sum of the public and the "
                                          "private attribute", "from": "instructions", "checks": ["method"]})
    assert implements(derived, "pkg/_cls.py", line) is None
    marked = Requirement.model_validate({"id": "docs", "says": "every public method has a docstring",
                                         "from": "instructions", "checks": ["docs"],
                                         "code": [{"file": "pkg/_cls.py", "line": r'^\s*"""', "docstrings": True}]})
    assert implements(marked, "pkg/_cls.py", line) == 'code: pkg/_cls.py /^\\s*"""/'
    assert implements(marked, "pkg/other.py", line) is None
    # a marker without docstrings: true never marks a docstring that happens to name its words
    by_name = Requirement.model_validate({"id": "sum", "says": "method() returns the sum", "from": "instructions",
                                          "checks": ["method"], "code": [{"file": "pkg/*.py", "line": "attribute"}]})
    assert implements(by_name, "pkg/_cls.py", line) is None
    assert implements(by_name, "pkg/_cls.py", "        return self.attribute + 1") is not None
