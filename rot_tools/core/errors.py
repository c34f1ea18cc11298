"""The one exception type of rot_tools, and the float errors its engine meets."""

__all__ = ['RotationError']


class RotationError(ValueError):
    """Invalid input to a rot_tools function; the message says what and by how much."""


FLOAT_ERRORS = (ArithmeticError, ValueError)
"""What Python's float arithmetic and math module raise where NumPy gives inf or NaN."""
