def sample_function_for_square_of_sum(a: float, b: float) -> float:
    """Return the square of the sum, (a + b)**2 = a**2 + 2*a*b + b**2."""
    # TODO: compute and return the square of the sum of a and b
    raise NotImplementedError('sample_function_for_square_of_sum')
