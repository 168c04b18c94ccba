import cmath
import math

import pytest

from bldclab.errors import BldclabError
from bldclab.model.design import pi_gains


def test_paper_design_is_pole_zero_cancellation():
    kp, ki = pi_gains(0.1, 150e-6, 1000.0, 90.0)
    wc = 2 * math.pi * 1000
    assert kp == pytest.approx(wc * 150e-6)
    assert ki == pytest.approx(wc * 0.1)


@pytest.mark.parametrize("R, L, f, pm, delay", [(0.1, 150e-6, 1000, 60, 53.6e-6), (0.059, 0.58e-3, 500, 75, 5e-5),
                                                 (0.0, 1e-4, 800, 80, 0.0)])
def test_crossover_and_margin_hold(R, L, f, pm, delay):
    kp, ki = pi_gains(R, L, f, pm, delay)
    w = 2 * math.pi * f
    loop = (kp + ki / (1j * w)) * cmath.exp(-1j * w * delay) / (R + 1j * w * L)
    assert abs(loop) == pytest.approx(1.0, rel=1e-9)
    assert math.degrees(cmath.phase(loop)) + 180 == pytest.approx(pm, abs=1e-6)


def test_infeasible_margin_is_an_error():
    with pytest.raises(BldclabError, match="cannot give"):
        pi_gains(0.1, 150e-6, 5000, 89, 200e-6)
    with pytest.raises(BldclabError):
        pi_gains(0.1, -1e-6, 1000)
