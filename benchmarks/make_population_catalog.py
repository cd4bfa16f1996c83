"""Write a seeded LDC-style galactic-binary catalog (ECSV) for examples, tests and benchmarks.

    python benchmarks/make_population_catalog.py -n 200 --seed 13 \
        -o catalogs/population/ldc-200.ecsv

Galactic-like but simple: f log-uniform in 1–20 mHz, chirp mass 0.2–0.6 M_sun (masses drawn
around it), ḟ from the GR chirp, distance 0.3–10 kpc, amplitude from (M_c, f, d), isotropic
inclination, uniform ψ, φ₀ and sky (ecliptic), a V magnitude from a 10 M_V white dwarf at d,
zero eccentricity. Row 1 is face-on (ι = 0: the Fisher matrix cannot constrain φ) so every
run exercises the "unconstrained" status.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ucbplan.core.binary import fdot_gw_only
from ucbplan.core.constants import C_M_S, G_SI, KPC_M, MSUN_KG


def make(n: int, seed: int):
    """The catalog as an astropy Table (LDC column names, units)."""
    from astropy.table import Table

    rng = np.random.default_rng(seed)
    f = 10 ** rng.uniform(math.log10(1e-3), math.log10(2e-2), n)
    m1 = rng.uniform(0.3, 0.8, n)
    m2 = rng.uniform(0.2, 1.0, n) * m1
    mc = (m1 * m2) ** 0.6 / (m1 + m2) ** 0.2
    fdot = fdot_gw_only(mc * MSUN_KG, f)
    d_kpc = rng.uniform(0.3, 10.0, n)
    amp = 2 * (G_SI * mc * MSUN_KG) ** (5 / 3) * (math.pi * f) ** (2 / 3)
    amp = amp / (C_M_S**4 * d_kpc * KPC_M)
    inc = np.arccos(rng.uniform(-1.0, 1.0, n))
    inc[0] = 0.0
    vmag = 10.0 + 5 * np.log10(d_kpc * 100.0) + rng.normal(0.0, 0.5, n)
    tab = Table()
    tab["Name"] = [f"GB{seed:02d}-{i + 1:05d}" for i in range(n)]
    tab["Frequency"] = f
    tab["Frequency"].unit = "Hz"
    tab["FrequencyDerivative"] = fdot
    tab["FrequencyDerivative"].unit = "Hz / s"
    tab["Amplitude"] = amp
    tab["EclipticLatitude"] = np.arcsin(rng.uniform(-1.0, 1.0, n))
    tab["EclipticLatitude"].unit = "rad"
    tab["EclipticLongitude"] = rng.uniform(0.0, 2 * math.pi, n)
    tab["EclipticLongitude"].unit = "rad"
    tab["Inclination"] = inc
    tab["Inclination"].unit = "rad"
    tab["Polarization"] = rng.uniform(0.0, math.pi, n)
    tab["Polarization"].unit = "rad"
    tab["InitialPhase"] = rng.uniform(0.0, 2 * math.pi, n)
    tab["InitialPhase"].unit = "rad"
    tab["Magnitude"] = np.round(vmag, 2)
    tab["Magnitude"].unit = "mag"
    tab["Distance"] = np.round(d_kpc, 4)
    tab["Distance"].unit = "kpc"
    tab["Mass1"] = np.round(m1, 4)
    tab["Mass1"].unit = "solMass"
    tab["Mass2"] = np.round(m2, 4)
    tab["Mass2"].unit = "solMass"
    tab.meta["description"] = (
        f"Synthetic LDC-style galactic-binary catalog ({n} sources, seed {seed}) written by "
        "benchmarks/make_population_catalog.py; parameters at the start of the LISA observation."
    )
    return tab


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=13)
    ap.add_argument("-o", "--output", type=Path, required=True)
    ap.add_argument("--hdf5", action="store_true", help="write an LDC-like HDF5 compound table")
    args = ap.parse_args(argv)
    tab = make(args.n, args.seed)
    if args.hdf5:
        import h5py

        arr = tab.as_array()
        with h5py.File(args.output, "w") as fh:
            dt = [(n, "S16" if n == "Name" else "f8") for n in tab.colnames]
            fh.create_dataset("H5LISA/GWSources/GalBinaries", data=np.array(arr, dtype=dt))
    else:
        tab.write(args.output, format="ascii.ecsv", overwrite=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
