"""E3, the stable-zone boundary v₀*(ΔF) and its exponent: the field model's map (`field`) and the 3D rod's boundary point by point (`rod3d`)."""

from .field import e3 as e3
