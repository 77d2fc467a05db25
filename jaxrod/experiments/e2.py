"""E2: the six phase portraits of the single-mode model against the analytic stable zone."""

from __future__ import annotations




__all__ = ['e2']


def e2(out, quick, progress):
    from ..figures import phase_portraits

    agreement = phase_portraits(out, n_grid=8 if quick == "tiny" else 12 if quick else 24)
    return {"grid_agreement_simulated_vs_analytic": agreement}

