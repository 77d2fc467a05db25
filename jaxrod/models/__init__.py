from .base import AbstractModel as AbstractModel
from .single_mode import SingleMode as SingleMode
from .single_mode import exact_solution as exact_solution
