"""E4, the critical load ΔF*(μ) under sine, random-velocity and random-position perturbations: the field model (`field`) and the 3D rod (`rod3d`)."""

from .field import e4 as e4
