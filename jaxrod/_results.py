"""Result codes: the status of a run lives in the data, not in exceptions."""

from __future__ import annotations

import numpy as np

__all__ = ["RESULTS"]


class RESULTS:
    """Integer result codes stored per run (and per sweep member).

    A vmapped run never aborts for one bad member: each member carries one of these codes.
    `jaxrod.simulate(..., throw=True)` turns a non-zero code into an error for single runs.
    """

    successful = 0
    nonfinite = 1
    step_limit = 2
    max_steps = 3
    invalid_input = 4
    inadequate = 5
    tolerance = 6

    messages = {
        0: "successful",
        1: "the state became non-finite (NaN or inf)",
        2: "the time step is above the integrator's stability limit",
        3: "the maximum number of steps (or phases) was reached before t1",
        4: "an input value is outside its valid range",
        5: "the scheme is not adequate for this run (the 3D rod past the wall's wrinkling load with the implicit "
           "scheme's local friction pass: use ImplicitLeapfrog(coupled=True) or the explicit leapfrog)",
        6: "the error-controlled step reached its smallest step with the error estimate above the tolerance "
           "(loosen rtol/atol or lower dt_min)",
    }

    @classmethod
    def describe(cls, code) -> str:
        """A human-readable message for a code (host-side)."""
        return cls.messages.get(int(np.asarray(code)), f"unknown result code {code!r}")
