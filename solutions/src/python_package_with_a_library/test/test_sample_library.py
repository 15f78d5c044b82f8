"""Unit tests of the library: `colcon test` runs them with pytest (setup.py: tests_require=['pytest'])."""

import pytest

from python_package_with_a_library.sample_python_library import SampleClass
from python_package_with_a_library.sample_python_library import sample_function_for_square_of_sum


# Pairs chosen so that plausible wrong formulas disagree with (a + b)**2:
# (1, 2) tells it from a**2 + b**2 and from 2*(a + b); (-3, 1) from a version that drops
# the signs; (0.5, 0.25) from one that rounds to whole numbers; (2, -2) gives zero.
@pytest.mark.parametrize(('a', 'b', 'expected'), [
    (1, 2, 9),
    (-3, 1, 4),
    (0.5, 0.25, 0.5625),
    (2, -2, 0),
    (-1.5, -2.5, 16.0),
])
def test_square_of_sum(a, b, expected):
    assert sample_function_for_square_of_sum(a, b) == pytest.approx(expected)


def test_each_instance_keeps_its_own_name():
    first = SampleClass('Alice')
    second = SampleClass(name='qyOXLBEtzZ')  # ten random letters, as the next lesson's node makes
    assert first.get_name() == 'Alice'
    assert second.get_name() == 'qyOXLBEtzZ'
