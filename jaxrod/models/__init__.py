from .base import AbstractModel as AbstractModel
from .field import FieldModel as FieldModel
from .galerkin import GalerkinModel as GalerkinModel
from .single_mode import SingleMode as SingleMode
from .single_mode import exact_solution as exact_solution
