"""Write ``catalogs/fiducial-eccentric-velocities.csv``: a seeded exact-Keplerian SB2 example.

Three targeted sessions (20 orbits each, 8 exposures of P_b/8 per orbit centred on u★ = kπ/4, the
epochs found with the ephemeris' u(t★) = u★ solver) 40 and 90 days after the end of the LISA
observation of ``catalogs/fiducial-eccentric.yaml``. Velocities follow the exact Keplerian orbit
(Kepler's equation; tests/support/reduce_synth.py), averaged over each exposure by
Gauss–Legendre quadrature, with γ_j = v_CM + z_j + orbital terms (z_j = G M_j/(R_j c),
Eggleton's WD radii),
M1 = 0.347, M2 = 0.285 M☉, v_CM = 25 km/s, Gaussian noise σ_v = 15 km/s (seed 20370101).

Usage: ``python benchmarks/make_example_velocities.py [--out FILE] [--seed S] [--a-los A]``
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from support.reduce_synth import exposure_factor  # noqa: E402

from ucbplan.core import binary, constants, ephemeris  # noqa: E402
from ucbplan.targets import Target, load_target  # noqa: E402

M1, M2 = 0.347, 0.285
V_CM = 25.0
SIGMA_V = 15.0


def true_k_gamma(t: Target, m1: float = M1, m2: float = M2) -> tuple[float, float, float, float]:
    """K1, K2 (Kepler from the masses) and γ1, γ2 (v_CM + redshift + orbital terms) [km/s]."""
    p = t.params
    nb = math.pi * p.f_gw - p.omega_dot
    e = p.eccentricity
    assert t.cos_inclination is not None
    sin_i = math.sqrt(1 - t.cos_inclination**2)
    mt = (m1 + m2) * constants.MSUN_KG
    a = (constants.G_SI * mt / nb**2) ** (1 / 3)
    k_tot = nb * a * sin_i / math.sqrt(1 - e * e) / 1e3
    k1, k2 = k_tot * m2 / (m1 + m2), k_tot * m1 / (m1 + m2)
    r1 = float(binary.radius_eggleton(m1)) * constants.RSUN_M
    r2 = float(binary.radius_eggleton(m2)) * constants.RSUN_M
    G, c = constants.G_SI, constants.C_M_S
    z1 = G * m1 * constants.MSUN_KG / (r1 * c) / 1e3
    z2 = G * m2 * constants.MSUN_KG / (r2 * c) / 1e3
    # companion potential + transverse Doppler: G M_other/(ac) + v_j²/(2c) (Sec. 3.1.2)
    o1 = (
        G * m2 * constants.MSUN_KG / (a * c) + G * (m2 * constants.MSUN_KG) ** 2 / (mt * a * 2 * c)
    ) / 1e3
    o2 = (
        G * m1 * constants.MSUN_KG / (a * c) + G * (m1 * constants.MSUN_KG) ** 2 / (mt * a * 2 * c)
    ) / 1e3
    return k1, k2, V_CM + z1 + o1, V_CM + z2 + o2


def targeted_times(t: Target, tau0: float, n_orbits: int) -> tuple[np.ndarray, np.ndarray]:
    """Mid-exposure τ and u★ of 8 exposures per orbit centred on u★ = kπ/4 over n_orbits."""
    p = t.params
    pb = 2 * math.pi / (math.pi * p.f_gw - p.omega_dot)
    taus, us = [], []
    for k in range(8):
        u_star = k * math.pi / 4
        _, dt, _, origin = ephemeris.solve_u(p, tau0, tau0 + n_orbits * pb, u_star)
        taus.append(origin + np.asarray(dt))
        us.append(np.full(len(dt), u_star))
    tau = np.concatenate(taus)
    u = np.concatenate(us)
    order = np.argsort(tau)
    return tau[order], u[order]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--target", type=Path, default=ROOT / "catalogs/fiducial-eccentric.yaml")
    ap.add_argument("--out", type=Path, default=ROOT / "catalogs/fiducial-eccentric-velocities.csv")
    ap.add_argument("--seed", type=int, default=20370101)
    ap.add_argument("--a-los", type=float, default=0.0, help="injected l.o.s. acceleration [m/s²]")
    args = ap.parse_args(argv)
    t = load_target(args.target)
    p = t.params
    pb = 2 * math.pi / (math.pi * p.f_gw - p.omega_dot)
    k1, k2, g1, g2 = true_k_gamma(t)
    rng = np.random.default_rng(args.seed)
    end = 0.5 * t.t_obs_s
    rows = []
    for label, start_d in (("S1", 10.0), ("S2", 50.0), ("S3", 100.0)):
        tau, ustar = targeted_times(t, end + start_d * 86400.0, 20)
        F = exposure_factor(p, tau, pb / 8)
        dv_cm = -args.a_los * (tau - end) / 1e3
        v1 = g1 + dv_cm + k1 * F + rng.normal(0, SIGMA_V, tau.size)
        v2 = g2 + dv_cm - k2 * F + rng.normal(0, SIGMA_V, tau.size)
        jd = (t.t_ref.tdb.jd1 - 0.0) + (t.t_ref.tdb.jd2 + tau / 86400.0)
        for i in range(tau.size):
            rows.append(
                f"{jd[i]:.10f},{pb / 8:.4f},{v1[i]:.3f},{SIGMA_V:.1f},{v2[i]:.3f},"
                f"{SIGMA_V:.1f},{label},{ustar[i]:.6f}"
            )
    header = (
        f"# {t.name}: exact Keplerian SB2 example (benchmarks/make_example_velocities.py, "
        f"seed {args.seed}); truth K1={k1:.3f} K2={k2:.3f} gamma1={g1:.3f} "
        f"gamma2={g2:.3f} km/s, a_los={args.a_los} m/s2\n"
        "bjd_tdb,exptime_s,v1,sigma_v1,v2,sigma_v2,session,u_star\n"
    )
    args.out.write_text(header + "\n".join(rows) + "\n", encoding="utf-8")
    print(f"wrote {len(rows)} spectra to {args.out}")


if __name__ == "__main__":
    main()
