"""
rot_tools: rotations and rigid motions without quaternions, for one item or a batch.

Plain NumPy (no ROS import anywhere in this package's math). Angles are radians, arrays
float64, ``...`` any leading batch shape. Invalid input raises RotationError (a ValueError).
The public names are those of each core module's ``__all__``, imported below.
"""

from rot_tools import core
from rot_tools.core.axis_angle import *  # noqa: F401,F403
from rot_tools.core.covariance import *  # noqa: F401,F403
from rot_tools.core.decomposition import *  # noqa: F401,F403
from rot_tools.core.errors import *  # noqa: F401,F403
from rot_tools.core.euler import *  # noqa: F401,F403
from rot_tools.core.fitting import *  # noqa: F401,F403
from rot_tools.core.hand_eye import *  # noqa: F401,F403
from rot_tools.core.imu import *  # noqa: F401,F403
from rot_tools.core.rigid import *  # noqa: F401,F403
from rot_tools.core.screw import *  # noqa: F401,F403
from rot_tools.core.so3 import *  # noqa: F401,F403
from rot_tools.core.trajectory import *  # noqa: F401,F403
from rot_tools.core.transform_tree import *  # noqa: F401,F403

__all__ = [
    *core.axis_angle.__all__,
    *core.covariance.__all__,
    *core.decomposition.__all__,
    *core.errors.__all__,
    *core.euler.__all__,
    *core.fitting.__all__,
    *core.hand_eye.__all__,
    *core.imu.__all__,
    *core.rigid.__all__,
    *core.screw.__all__,
    *core.so3.__all__,
    *core.trajectory.__all__,
    *core.transform_tree.__all__,
]
