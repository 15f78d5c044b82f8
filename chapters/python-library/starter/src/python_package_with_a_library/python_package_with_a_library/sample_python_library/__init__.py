"""The library's public face: other packages import from here, not from the private modules."""

# TODO: import SampleClass and sample_function_for_square_of_sum from the two private
#       modules of this folder, so that users can write
#       from python_package_with_a_library.sample_python_library import SampleClass
