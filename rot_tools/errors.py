"""The one exception type of rot_tools."""


class RotationError(ValueError):
    """Invalid input to a rot_tools function; the message says what and by how much."""
