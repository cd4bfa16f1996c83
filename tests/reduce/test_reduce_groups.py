"""group_spectra (one sort + bincount) against a brute-force per-(session, u★) loop."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.reduce.groups import ANCHOR_U, MATCH_TOL_RAD, assign_anchors, group_spectra


def _brute(sessions, tau, u, us, vels, sigs, K, G, lk, lkap):  # type: ignore[no-untyped-def]
    out = []
    keys = sorted({(s, a) for s, a in zip(sessions, us, strict=True) if np.isfinite(a)})
    for s, a in keys:
        m = np.array([x == s for x in sessions]) & (us == a)
        comp = []
        for j, (v, sg) in enumerate(zip(vels, sigs, strict=True)):
            sk = (1.0 if j == 0 else -1.0) * K[j]
            w = 1.0 / sg[m] ** 2
            vc = v[m] - sk * lk[m] * (np.cos(u[m]) - math.cos(a))
            gam = v[m] - sk * G[m]
            comp.append(
                (np.sum(w * vc) / w.sum(), 1 / math.sqrt(w.sum()), np.sum(w * gam) / w.sum())
            )
        out.append((s, a, tau[m].mean(), int(m.sum()), comp, lk[m].mean(), lkap[m].mean()))
    out.sort(key=lambda r: r[2])
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_groups_match_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 500
    sessions = [f"night{k}" for k in rng.integers(0, 7, n)]
    tau = rng.uniform(0, 1e6, n)
    u = rng.uniform(0, 2 * math.pi, n)
    us = rng.choice([*ANCHOR_U, np.nan], n)
    vels = [rng.normal(0, 300, n), rng.normal(0, 300, n)]
    sigs = [rng.uniform(5, 20, n), rng.uniform(5, 20, n)]
    G, lk, lkap = rng.normal(size=n), rng.uniform(0.9, 1, n), rng.uniform(0.9, 1, n)
    K = (500.0, 600.0)
    args = {"sessions": sessions, "tau_s": tau, "u_rad": u, "u_star": us, "velocities": vels}
    args |= {"sigmas": sigs, "K": K, "design": G, "lam_k": lk, "lam_kappa": lkap}
    got = group_spectra(**args)  # type: ignore[arg-type]
    ref = _brute(sessions, tau, u, us, vels, sigs, K, G, lk, lkap)
    assert len(got) == len(ref) > 20
    # cos u given by the caller (the orbit track's): the same groups
    assert group_spectra(**args, cos_u=np.cos(u)) == got  # type: ignore[arg-type]
    for g, (s, a, t, k, comp, mk, mkap) in zip(got, ref, strict=True):
        assert (g.session, g.u_star, g.n) == (s, a, k)
        assert g.tau_s == pytest.approx(t, rel=1e-12)
        assert (g.lam_k, g.lam_kappa) == pytest.approx((mk, mkap), rel=1e-12)
        for j, (v, sg, gm) in enumerate(comp):
            assert g.v[j] == pytest.approx(v, rel=1e-12, abs=1e-9)
            assert g.sigma[j] == pytest.approx(sg, rel=1e-12)
            assert g.gamma_est[j] == pytest.approx(gm, rel=1e-12, abs=1e-9)
            assert g.gamma_sigma[j] == g.sigma[j]


def test_no_assigned_spectra_give_no_groups() -> None:
    out = group_spectra(
        sessions=["a", "b"],
        tau_s=[0.0, 1.0],
        u_rad=[0.0, 1.0],
        u_star=[np.nan, np.nan],
        velocities=[[1.0, 2.0]],
        sigmas=[[1.0, 1.0]],
        K=(1.0,),
        design=[0.0, 0.0],
        lam_k=1.0,
        lam_kappa=1.0,
    )
    assert out == []


def _anchors_by_table(u_rad: np.ndarray) -> np.ndarray:
    """The nearest anchor within tolerance from the full spectrum-by-anchor distance table."""
    u = np.asarray(u_rad, float) % (2.0 * math.pi)
    anchors = np.asarray(ANCHOR_U)
    d = np.abs((u[:, None] - anchors[None, :] + math.pi) % (2.0 * math.pi) - math.pi)
    k = np.argmin(d, axis=1)
    ok = d[np.arange(u.size), k] <= MATCH_TOL_RAD
    return np.where(ok, anchors[k], np.nan)


def test_assign_anchors_nearest_only() -> None:
    """Only the nearest anchor's distance is computed: the same u★ as the full table, on random
    phases (unwrapped over ±20 turns) and on the tolerance's edges, bit for bit."""
    rng = np.random.default_rng(4)
    edges = np.array([a + s * MATCH_TOL_RAD for a in (*ANCHOR_U, 2 * math.pi) for s in (-1, 1)])
    edges = np.concatenate([edges, np.nextafter(edges, 0.0), np.nextafter(edges, 10.0)])
    quarter = np.arange(8) * 0.25 * math.pi  # half-way between anchors: none
    u = np.concatenate([rng.uniform(-40 * math.pi, 40 * math.pi, 20_000), edges, quarter, [0.0]])
    got = assign_anchors(u)
    np.testing.assert_array_equal(got, _anchors_by_table(u))
    # independent values: 0.3 rad is within π/8 of 0, 0.4 rad is not; 2π − 0.1 → 0
    assert assign_anchors(np.array([0.3, 2 * math.pi - 0.1, 1.5 * math.pi + 0.39])).tolist() == [
        0.0,
        0.0,
        1.5 * math.pi,
    ]
    assert np.isnan(assign_anchors(np.array([0.4, np.nan]))).all()


_labels = st.lists(
    st.sampled_from(["S1", "S10", "S2", "01", "1", "night é", "A\x00", "A", "Z", "a", "S100"]),
    min_size=1,
    max_size=60,
)


@settings(max_examples=60, deadline=None)
@given(_labels)
def test_session_codes_are_numpys_unique_of_every_spectrum(labels: list[str]) -> None:
    """Issue 34: the session codes come from the distinct labels alone; they must be
    ``np.unique(labels, return_inverse=True)`` of all spectra (its sorted order, its reading of
    a trailing NUL), which decides the groups' order and labels."""
    from ucbplan.reduce.groups import _session_codes

    names, code = _session_codes(tuple(labels))
    ref_names, ref_code = np.unique(np.asarray(labels), return_inverse=True)
    assert names.tolist() == ref_names.tolist()
    assert code.tolist() == ref_code.reshape(-1).tolist()
