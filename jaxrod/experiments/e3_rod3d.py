"""E3's 3D boundary, now `jaxrod.experiments.e3.rod3d`: this module keeps the old name one release."""

from .e3.rod3d import *  # noqa: F401,F403
from .e3.rod3d import _append, _bisect, _runs_of, DT_RTOL, RUN_COLUMNS, SINK  # noqa: F401
