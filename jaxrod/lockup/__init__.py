"""Force transfer and lock-up of a rod pushed into a long horizontal channel (docs/physics.md §8).

[`jaxrod.lockup.closed_forms`][] holds the soft-string closed forms: the onset loads, the wall
force per length of a straight, sinusoidal and helical section, the force that reaches the far
end, its largest value against the length, and the lock-up length.
[`jaxrod.lockup.si`][] makes the rod and channel of a real tubing given in SI units and
gives its case (μL/ℓ, r/ℓ) and units (F₀, ℓ).
"""

from . import chain as chain
from . import closed_forms as closed_forms
from . import si as si
from . import verdict as verdict
from .chain import (
    far_force as far_force,
)
from .chain import (
    far_force_max as far_force_max,
)
from .chain import (
    force_profile as force_profile,
)
from .closed_forms import (
    force_unit as force_unit,
)
from .closed_forms import (
    helical_far_force_max as helical_far_force_max,
)
from .closed_forms import (
    helical_lockup_length as helical_lockup_length,
)
from .closed_forms import (
    helical_onset as helical_onset,
)
from .closed_forms import (
    helical_transfer as helical_transfer,
)
from .closed_forms import (
    helical_wall_force as helical_wall_force,
)
from .closed_forms import (
    helix_pitch as helix_pitch,
)
from .closed_forms import (
    length_unit as length_unit,
)
from .chain import (
    lockup_length as lockup_length,
)
from .chain import (
    section_extents as section_extents,
)
from .closed_forms import (
    sinusoidal_onset as sinusoidal_onset,
)
from .closed_forms import (
    sinusoidal_transfer as sinusoidal_transfer,
)
from .closed_forms import (
    straight_transfer as straight_transfer,
)
from .closed_forms import (
    transfer as transfer,
)
from .closed_forms import (
    transfer_length as transfer_length,
)
from .chain import (
    wall_force as wall_force,
)
from .si import case as case
from .si import tubing as tubing

__all__ = [
    "case",
    "chain",
    "closed_forms",
    "far_force",
    "far_force_max",
    "force_profile",
    "force_unit",
    "helical_far_force_max",
    "helical_lockup_length",
    "helical_onset",
    "helical_transfer",
    "helical_wall_force",
    "helix_pitch",
    "length_unit",
    "lockup_length",
    "section_extents",
    "si",
    "sinusoidal_onset",
    "sinusoidal_transfer",
    "straight_transfer",
    "transfer",
    "transfer_length",
    "tubing",
    "wall_force",
]
