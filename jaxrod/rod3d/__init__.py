"""The full model: a 3D discrete Cosserat rod in the channel (see `jaxrod.rod3d.model`)."""

from .model import Rod3D as Rod3D
from .recipe import Rod3DRecipe as Rod3DRecipe
from .state import Rod3DForces as Rod3DForces
from .state import Rod3DPosition as Rod3DPosition
from .state import Rod3DVelocity as Rod3DVelocity
from .state import sine_velocity as sine_velocity
from .stiffness import step_limit as step_limit
from .hessian import IMPLICIT_DT as IMPLICIT_DT
