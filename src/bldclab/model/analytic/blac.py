"""Paper 1 section IV.B: the equivalent PM BLAC motor (sinusoidal back-EMF of the same peak).

Its nominal torque and base speed, and its torque over speed.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ._common import SQRT3, FloatOrArray, _out, _speed, _theta

__all__ = [
    "T_BLAC_N_PU",
    "omega_blac_B_pu",
    "t_blac_pu",
]


#: Nominal torque of the equivalent PM BLAC motor, per unit of T_N: ``sqrt(3)/2`` ~ 0.866, paper 1 IV.B.
T_BLAC_N_PU = SQRT3 / 2.0




def omega_blac_B_pu(Theta_m: float) -> float:
    """Return the base speed of the equivalent PM BLAC motor (per unit of Omega_0), paper 1 section IV.B.

    The equivalent BLAC motor has a sinusoidal back-EMF of peak ``k_phi Omega`` (the BLDC flat top) and
    carries ``I_s,N`` in phase with it. Its peak line-to-line voltage is
    ``sqrt(3) Omega sqrt(k_phi^2 + (p L I_s,N)^2)``; equating it to ``V_N`` gives
    ``W_B = 2 / (sqrt(3) sqrt(1 + 16 Theta_m^2 / 3))``, above 1: it outruns the BLDC motor, whose line-to-line
    back-EMF is ``2 k_phi Omega`` instead of ``sqrt(3) k_phi Omega``.

    Parameters
    ----------
    Theta_m : float
        Motor-specific parameter (22) of the BLDC motor (rad).

    Returns
    -------
    float
        Speed (per unit of Omega_0).

    """
    th = _theta(Theta_m)
    return 2.0 / (SQRT3 * math.sqrt(1.0 + 16.0 * th**2 / 3.0))


def t_blac_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Torque of the equivalent PM BLAC motor at nominal rms current, paper 1 section IV.B.

    ``sqrt(3)/2`` (0.866 of the BLDC nominal torque, [5] in the paper) up to :func:`omega_blac_B_pu`; above it
    the current in phase with the back-EMF is reduced to keep the peak line-to-line voltage at ``V_N`` (no
    flux weakening): ``T_pu = 3/4 sqrt(4 / (3 W^2) - 1) / (2 Theta_m)``, zero from ``W = 2/sqrt(3)``.

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) of the BLDC motor (rad).

    Returns
    -------
    float or ndarray
        Torque (per unit of T_N).

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    with np.errstate(divide="ignore", invalid="ignore"):
        i_pu = np.sqrt(np.clip(4.0 / (3.0 * w**2) - 1.0, 0.0, None)) / (2.0 * th)  # current / I_N
    i_pu = np.where(w == 0.0, 2.0 / SQRT3, np.minimum(i_pu, 2.0 / SQRT3))
    return _out(0.75 * i_pu)
