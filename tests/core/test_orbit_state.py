"""orbit_state (one phase evaluation) is bit-identical to phase_asc, ll_pair and arg_latitude."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.core.params import PhaseParams
from ucbplan.core.phase import arg_latitude, ll_pair, orbit_state, phase_asc


@settings(max_examples=40, deadline=None)
@given(
    phase=st.floats(0, 6.28),
    f=st.floats(1e-4, 3e-2),
    fdot=st.floats(-1e-15, 1e-14),
    eta=st.floats(-0.1, 0.1),
    kappa=st.floats(-0.1, 0.1),
    wdot=st.floats(-1e-6, 1e-6),
    seed=st.integers(0, 2**31),
)
def test_orbit_state_identical(
    phase: float, f: float, fdot: float, eta: float, kappa: float, wdot: float, seed: int
) -> None:
    p = PhaseParams(phase, f, fdot, 0.0, eta, kappa, wdot)
    tau = np.random.default_rng(seed).uniform(-3e8, 3e8, 257)
    phi, e, k, u = orbit_state(p, tau)
    e_ref, k_ref = ll_pair(p, tau)
    assert np.array_equal(phi, phase_asc(p, tau))
    assert np.array_equal(e, e_ref) and np.array_equal(k, k_ref)
    assert np.array_equal(u, arg_latitude(p, tau, star=1))
