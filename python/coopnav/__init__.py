"""coopnav from Python: cooperative navigation of AUV teams.

Thin bindings over the coopnav Rust libraries (the same code the ``coopnav`` CLI runs, so the same
inputs and seed give the same numbers):

* scenarios: :class:`Scenario` (``load``, ``from_toml``, ``from_dict``, ``example``);
* planner: :class:`Planner` (one decision at a time) and :func:`plan` (a whole pre-deployment plan);
* navigation: :class:`AuvEkf`, :class:`SurfaceEkf` and :func:`postprocess` (EKF + RTS smoother);
* channel: :class:`TransmissionLoss` and :func:`p_success`;
* simulation: :func:`simulate` and :func:`monte_carlo`.

Bad input raises ``ValueError`` naming the field. Long calls release the GIL; ``simulate`` and
``monte_carlo`` stop on Ctrl-C (``KeyboardInterrupt``). Units are SI; headings are math radians
(0 = east, counter-clockwise) except where a file format says compass degrees.
"""

import numpy as np

from ._coopnav import (
    AuvEkf,
    Planner,
    Scenario,
    SurfaceEkf,
    TransmissionLoss,
    __version__,
    monte_carlo,
    plan,
    postprocess,
    simulate,
)
from ._coopnav import p_success as _p_success

__all__ = [
    "AuvEkf",
    "Planner",
    "Scenario",
    "SurfaceEkf",
    "TransmissionLoss",
    "__version__",
    "monte_carlo",
    "p_success",
    "plan",
    "postprocess",
    "simulate",
]


def p_success(rate, tl_db, noise_db=0.0, model=None):
    """Packet-success likelihood at WHOI ``rate`` for transmission loss ``tl_db`` (dB; a number or
    an array of any shape, the result has the same shape), with ``noise_db`` extra ambient noise."""
    tl = np.asarray(tl_db, dtype=np.float64)
    p = _p_success(rate, np.ascontiguousarray(tl.reshape(-1)), noise_db, model)
    return p.reshape(tl.shape) if tl.ndim else float(p[0])
