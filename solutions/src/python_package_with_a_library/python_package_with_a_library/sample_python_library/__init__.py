"""The library's public face: other packages import from here, not from the private modules."""

from python_package_with_a_library.sample_python_library._sample_class import SampleClass
from python_package_with_a_library.sample_python_library._sample_function import sample_function_for_square_of_sum

__all__ = ['SampleClass', 'sample_function_for_square_of_sum']
