"""The full model: a 3D discrete Cosserat rod in the channel (see `jaxrod.rod3d.model`)."""

from .model import Rod3D as Rod3D
from .model import Rod3DState as Rod3DState
from .run import Rod3DSolution as Rod3DSolution
from .run import simulate_rod3d as simulate_rod3d
from .run import step_limit as step_limit
