"""Paper 2's controller with a wrong inductance estimate: feed-forward where the current stops, and ``adapt_L``.

Physics: where the current stops within the PWM period each period starts from zero, the duty comes from the
model alone and the pulse it gives scales as 1/L, so the mean torque is T* L_est / L. With ``adapt_L`` the
controller fits L to the measured rise of the pair current (core/ctrl/include/bldc/bc_lu.h).
"""

import pytest

import bldclab as bl
from bldclab.analysis.experiments import steady_state
from bldclab.errors import BldclabError

T_N_LU = 12.732395447351625  # lu-4kw's rated torque, 2 k_phi I_N (N m)


def _ratio(name: str, load: float, speed_pu: float, f: float, adapt: float) -> float:
    d = bl.load(name)
    t_ref = load * (T_N_LU if name == "lu-4kw" else d.T_N)
    p, _ = steady_state(d, bl.Lu(adapt_L=adapt), speed_pu * d.Omega_0, t_ref, estimate=d.scaled(L=f),
                        settle_time=0.05)
    return p.tau_mean / t_ref


@pytest.mark.slow
@pytest.mark.parametrize("f", [0.5, 0.7, 1.5])
def test_discontinuous_current_makes_the_law_feed_forward(f):
    """lu-4kw at 25 % load, 0.3 Omega_0: the current stops every period; the torque follows L_est / L."""
    assert _ratio("lu-4kw", 0.25, 0.3, f, 0.0) == pytest.approx(f, rel=0.03)


@pytest.mark.slow
@pytest.mark.parametrize("f", [0.5, 0.7, 1.5])
def test_adaptation_restores_the_torque_in_discontinuous_conduction(f):
    assert _ratio("lu-4kw", 0.25, 0.3, f, 0.05) == pytest.approx(1.0, abs=0.01)


def test_adaptation_with_the_right_estimate_changes_little():
    """With L_est = L the fitted inductance stays at L: the torque moves by < 0.3 % at 25 % load."""
    a, b = _ratio("lu-4kw", 0.25, 0.3, 1.0, 0.0), _ratio("lu-4kw", 0.25, 0.3, 1.0, 0.05)
    assert abs(a - b) < 3e-3 and abs(b - 1.0) < 5e-3


@pytest.mark.slow
def test_continuous_current_needs_no_adaptation():
    """htm-48v at rated torque conducts continuously: the deadbeat law's fixed point ignores L_est (< 2 L)."""
    for f in (0.5, 1.5):
        assert _ratio("htm-48v", 1.0, 0.3, f, 0.0) == pytest.approx(1.0, abs=5e-3)


@pytest.mark.parametrize("bad", [-0.1, 1.5, float("nan"), True, "0.1"])
def test_adapt_gain_is_checked(bad):
    with pytest.raises(BldclabError) as e:
        bl.Lu(adapt_L=bad)
    assert e.value.field == "control.adapt_L"
