"""Figures (host-side; matplotlib is imported lazily inside each function)."""

from .phase import phase_portraits as phase_portraits
