"""E5, the dominant mode at buckling under random perturbations: the field model (`field`) and the 3D rod (`rod3d`)."""

from .field import e5 as e5
