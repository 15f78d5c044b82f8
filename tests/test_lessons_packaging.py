"""Unit tests of the packaging lessons' grader helpers (graders/kit/packaging.py); no ROS needed.

The parsers judge the /rosout lines of ``use-python-library`` (seed ch. 15.1): they must
accept every reasonable way of printing the numbers, and still catch a wrong c.
"""

from __future__ import annotations

import inspect
import random
import string
from types import SimpleNamespace

import pytest

from ros2course.grade.checklist import Unmet, check_dependencies

from ros2course.grade.engine import load_grader

from ros2course.grade.session import GradingSession
from ros2course.kit.packaging import (
    classify,
    data_files_mapping,
    installed_subpackage,
    is_ten_letters,
    name_lines,
    parse_name_line,
    parse_square_line,
    read_setup_cfg,
    ros2_run_executable,
    rounding_error,
    setup_cfg_problems,
    square_lines,
    unpaired,
)

PACKAGING_GRADERS = ["workspace_setup", "simplest_python_package", "python_node_template", "python_library",
                     "use_python_library"]

# --- the square-of-sum line ------------------------------------------------------------


def _line(a, b, c, spec=""):
    return f"sample_function_for_square_of_sum({a:{spec}},{b:{spec}}) returned {c:{spec}}."


def test_seed_output_line_parses_and_is_right():
    # a line of the seed's own output (ch. 15.3)
    line = parse_square_line(
        "sample_function_for_square_of_sum(0.19395834493833486,1.3891603395040568) returned 2.506264769030609.")
    assert line is not None
    assert (line.a, line.b) == (0.19395834493833486, 1.3891603395040568)
    assert line.ranges_ok()
    assert line.square_ok()


@pytest.mark.parametrize("spec", ["", ".3f", ".2f", ".6g", ".4e", ".10f"])
def test_any_number_format_of_a_correct_node_passes(spec):
    rng = random.Random(1234)
    for _ in range(300):
        a, b = rng.uniform(0, 1), rng.uniform(1, 2)
        line = parse_square_line(_line(a, b, (a + b) ** 2, spec))
        assert line is not None, spec
        assert line.square_ok(), (spec, a, b)
        assert line.ranges_ok(), (spec, a, b)


def test_the_seed_formula_passes_like_the_exact_square():
    a, b = 0.1, 1.2
    assert parse_square_line(_line(a, b, a**2 + 2 * a * b + b**2)).square_ok()


@pytest.mark.parametrize(("wrong", "what"), [
    (lambda a, b: a**2 + b**2, "forgot 2ab"),
    (lambda a, b: (a + a) ** 2, "a twice"),
    (lambda a, b: (a + b) * 2, "doubled"),
    (lambda a, b: (a * b) ** 2, "product"),
])
def test_a_wrong_c_fails_at_full_precision(wrong, what):
    rng = random.Random(99)
    for _ in range(100):
        a, b = rng.uniform(0.01, 1), rng.uniform(1, 2)
        assert not parse_square_line(_line(a, b, wrong(a, b))).square_ok(), what


def test_a_wrong_c_fails_even_with_three_decimals():
    a, b = 0.5, 1.5
    assert not parse_square_line(_line(a, b, a**2 + b**2, ".3f")).square_ok()


def test_ranges():
    assert parse_square_line(_line(0.0, 1.0, 1.0)).ranges_ok()
    assert parse_square_line(_line(1.0, 2.0, 9.0)).ranges_ok()
    assert not parse_square_line(_line(0.5, 0.7, 1.44)).ranges_ok()   # b from [0, 1]
    assert not parse_square_line(_line(1.5, 1.5, 9.0)).ranges_ok()    # a above 1
    assert not parse_square_line(_line(-0.1, 1.5, 1.96)).ranges_ok()  # a negative


@pytest.mark.parametrize("text", [
    "sample_function_for_square_of_sum(0.5, 1.5) returned 4.0.",   # space after the comma
    "sample_function_for_square_of_sum(0.5,1.5) returned 4.0",     # no final period
    "sample_function_for_square_of_sum(.5,1.5) returned 4.",       # unusual but valid numbers
    "sample_function_for_square_of_sum(5e-01,1.5) returned 4.0.",
    "  sample_function_for_square_of_sum(0.5,1.5) returned 4.0.  ",
])
def test_tolerated_spellings(text):
    line = parse_square_line(text)
    assert line is not None
    assert line.square_ok()


@pytest.mark.parametrize("text", [
    "sample_function_for_square_of_sum(0.5,1.5) returns 4.0.",
    "square_of_sum(0.5,1.5) returned 4.0.",
    "sample_function_for_square_of_sum(0.5;1.5) returned 4.0.",
    "sample_function_for_square_of_sum(a,b) returned c.",
    "sample_function_for_square_of_sum(0.5,1.5) returned four.",
    "Printed 3 times.",
])
def test_other_lines_are_not_square_lines(text):
    assert parse_square_line(text) is None


@pytest.mark.parametrize(("text", "error"), [
    ("3", 0.5), ("0.125", 0.0005), ("1.5e-05", 5e-07), ("2.", 0.5), ("1E2", 50.0),
])
def test_rounding_error(text, error):
    assert rounding_error(text) == pytest.approx(error)


# --- the name line -------------------------------------------------------------------


def test_name_line_with_and_without_period():
    assert parse_name_line("sample_class_with_random_name.get_name() returned qyOXLBEtzZ.") == "qyOXLBEtzZ"
    # the seed's code listing (ch. 15.1) prints no final period
    assert parse_name_line("sample_class_with_random_name.get_name() returned qyOXLBEtzZ") == "qyOXLBEtzZ"
    assert parse_name_line("sample_class_with_random_name.get_name() returns qyOXLBEtzZ.") is None


def test_ten_letters():
    rng = random.Random(7)
    for _ in range(50):
        assert is_ten_letters("".join(rng.choice(string.ascii_letters) for _ in range(10)))
    for bad in ["abcdefgh", "abcdefghijk", "abcde12345", "abcdefghi ", "abcdéfghij", ""]:
        assert not is_ten_letters(bad), bad


def test_an_eleven_character_name_is_not_cut_to_ten():
    name = parse_name_line("sample_class_with_random_name.get_name() returned abcdefghijK.")
    assert name == "abcdefghijK"
    assert not is_ten_letters(name)


# --- pairing -------------------------------------------------------------------------


def test_classify():
    assert classify(_line(0.5, 1.5, 4.0)) == "square"
    assert classify("sample_class_with_random_name.get_name() returned qyOXLBEtzZ.") == "name"
    assert classify("hello") == "other"


def _ticks(*kinds_per_tick, period=0.5, within=0.001):
    """(kind, stamp) records: each tick's kinds logged ``within`` seconds apart, ticks ``period`` apart."""
    out = []
    for tick, kinds in enumerate(kinds_per_tick):
        out += [(kind, tick * period + i * within) for i, kind in enumerate(kinds)]
    return out


@pytest.mark.parametrize(("records", "bad"), [
    (_ticks(*[["square", "name"]] * 4), []),
    (_ticks(["square", "name"], ["square"]), []),               # the last name is still on its way
    (_ticks(*[["name", "square"]] * 3), [0, 1, 2, 3, 4]),  # names first: S N pairs straddle ticks
    (_ticks(["square"], ["square", "name"]), [0]),
    (_ticks(["name"], ["name"]), [0, 1]),
    (_ticks(["square"], ["name"]), [0, 1]),                     # one per tick, alternating
    ([], []),
])
def test_unpaired(records, bad):
    assert unpaired(records, max_gap=0.25) == bad


# --- setup.cfg and data_files -------------------------------------------------------------


def test_setup_cfg_template_is_right(tmp_path):
    cfg = tmp_path / "setup.cfg"
    cfg.write_text("[develop]\nscript_dir=$base/lib/pkg\n[install]\ninstall_scripts=$base/lib/pkg\n")
    assert setup_cfg_problems(cfg, "pkg") == []


def test_setup_cfg_dashed_keys_count(tmp_path):
    """The Foxy-era template wrote script-dir / install-scripts; setuptools still reads them."""
    cfg = tmp_path / "setup.cfg"
    cfg.write_text("[develop]\nscript-dir=$base/lib/pkg\n[install]\ninstall-scripts=$base/lib/pkg/\n")
    assert read_setup_cfg(cfg)["install"] == {"install_scripts": "$base/lib/pkg/"}
    assert setup_cfg_problems(cfg, "pkg") == []


def test_setup_cfg_problems_are_named(tmp_path):
    cfg = tmp_path / "setup.cfg"
    assert setup_cfg_problems(cfg, "pkg") == ["there is no setup.cfg"]
    cfg.write_text("[install]\ninstall_scripts=$base/lib\n")
    assert setup_cfg_problems(cfg, "pkg") == ["[develop] has no script_dir", "[install] install_scripts=$base/lib"]
    cfg.write_text("this is not an ini file")
    assert setup_cfg_problems(cfg, "pkg") == ["[develop] has no script_dir", "[install] has no install_scripts"]


def test_data_files_mapping_like_colcon():
    mapping = data_files_mapping([
        ["share/ament_index/resource_index/packages", ["resource/pkg"]],
        ("share/pkg/", ["./package.xml"]),
        "README.md",
        ["broken"],
    ])
    assert mapping == {
        "resource/pkg": "share/ament_index/resource_index/packages/pkg",
        "package.xml": "share/pkg/package.xml",
        "README.md": "README.md",
    }
    assert data_files_mapping(None) == {}


# --- the graders and their kit steps (a real GradingSession, no ROS) ---------------------


@pytest.mark.parametrize("name", PACKAGING_GRADERS)
def test_graders_are_ported_to_the_kit(name):
    """Valid needs, and none of the old skip helpers (issue "One grader kit")."""
    module = load_grader(name)
    check_dependencies(module.CHECKS)
    source = inspect.getsource(module)
    for old in ("skip_remaining", "graders._common", "import rclpy"):
        assert old not in source


def _session(tmp_path, checks):
    from ros2course.kit import Check

    return GradingSession(None, [Check(c, c, 1, needs=n) for c, n in checks], tmp_path, tmp_path / "log", {})


def test_ros2_run_executable_names_a_script_installed_to_bin(tmp_path):
    s = _session(tmp_path, [("executable", ())])
    s.find_executable = lambda package, name: (None, f"no {name} in install/{package}/lib/{package}")
    stray = tmp_path / "install" / "pkg" / "bin" / "exe"
    stray.parent.mkdir(parents=True)
    stray.write_text("#!/usr/bin/python3\n")
    with pytest.raises(Unmet):
        ros2_run_executable(s, "executable", "pkg", "exe")
    result = s.results["executable"]
    assert not result.passed
    assert "installed as install/pkg/bin/exe instead" in result.observed
    assert "install_scripts=$base/lib/pkg" in result.hint


def test_ros2_run_executable_returns_the_path(tmp_path):
    s = _session(tmp_path, [("executable", ())])
    s.find_executable = lambda package, name: (tmp_path / name, "found")
    assert ros2_run_executable(s, "executable", "pkg", "exe") == tmp_path / "exe"
    assert s.results["executable"].passed


def test_installed_subpackage(tmp_path):
    s = _session(tmp_path, [("installed", ())])
    top = tmp_path / "install" / "pkg" / "lib" / "python3.12" / "site-packages" / "pkg"
    top.mkdir(parents=True)
    (top / "__init__.py").write_text("")
    assert not installed_subpackage(s, "installed", "pkg", "sub")
    assert "holds __init__.py: no sub/" in s.results["installed"].observed
    (top / "sub").mkdir()
    (top / "sub" / "__init__.py").write_text("")
    assert installed_subpackage(s, "installed", "pkg", "sub")


def _record(text, t):
    return SimpleNamespace(msg=text, name="node", stamp=SimpleNamespace(sec=int(t), nanosec=int(t % 1 * 1e9)))


def test_square_and_name_lines_judge_a_correct_node(tmp_path):
    s = _session(tmp_path, [(c, ()) for c in ("ranges", "values", "name", "pairs", "differ")])
    records = []
    for tick in range(4):
        a, b = random.uniform(0, 1), random.uniform(1, 2)
        name = "".join(random.choice(string.ascii_letters) for _ in range(10))
        records += [_record(_line(a, b, (a + b) ** 2), tick * 0.5),
                    _record(f"sample_class_with_random_name.get_name() returned {name}.", tick * 0.5 + 0.001)]
    square_lines(s, "ranges", "values", [r for r in records if classify(r.msg) == "square"])
    name_lines(s, "name", "pairs", "differ", records, max_gap=0.25)
    assert all(result.passed for result in s.results.values()), s.results


def test_name_lines_without_names_fail_all_three(tmp_path):
    s = _session(tmp_path, [(c, ()) for c in ("name", "pairs", "differ")])
    name_lines(s, "name", "pairs", "differ", [_record(_line(0.5, 1.5, 4.0), 0.0)], max_gap=0.25)
    assert [r.passed for r in s.results.values()] == [False, False, False]
