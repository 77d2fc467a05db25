"""Figures (host-side; matplotlib is imported lazily inside each function)."""

from .phase import phase_portraits as phase_portraits
from .simulation import plot_simulation as plot_simulation

__all__ = ["phase_portraits", "plot_simulation"]
