"""E6, the full model's picture of buckling, and the random position at μ = 0.9: the field model (`field`) and the 3D rod (`rod3d`, part C)."""

from .field import e6 as e6
