"""Unit tests of the library: `colcon test` runs them with pytest.

Each test_* function is one test. A good test suite fails on every plausible
wrong version of the code: think of how the function or the class could be
wrong, and pick values that tell the right version from each wrong one.
"""

from python_package_with_a_library.sample_python_library import SampleClass
from python_package_with_a_library.sample_python_library import sample_function_for_square_of_sum


def test_square_of_sum():
    assert sample_function_for_square_of_sum(1, 1) == 4
    # TODO: (1, 1) gives 4 for (a + b) * 2 as well. Add pairs that tell (a + b)**2 apart from
    #       other formulas: negative numbers, floats (compare floats with pytest.approx).


def test_sample_class_keeps_its_name():
    # TODO: make instances of SampleClass and check what get_name() returns for each.
    assert SampleClass is not None
