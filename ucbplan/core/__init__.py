"""The physics core: parameter sets, the phase model u(t), t★ inversion, σ_u/T_valid, smearing.

Pure functions over SI floats; nothing here reads files, prints or imports a higher layer (a
target is anything shaped like :class:`~ucbplan.core.params.EphemerisSource`).

- :mod:`.params`: :class:`~.params.PhaseParams`, reference-epoch shifts, ``EphemerisSource``;
- :mod:`.phase`: GW phase, u(t), u̇, velocities, ∂u/∂θ (compensated arithmetic);
- :mod:`.ephemeris`: the inversion u(t★) = u★ and :func:`~.ephemeris.find_epochs`;
- :mod:`.forecast`: σ_u(t), tolerances, horizons T_valid (after a LISA observation, or before and
  after a timing ephemeris' T0);
- :mod:`.timing`: timing ephemerides (T0, P, Ṗ, P̈) as the phase model, and the comparison of two
  ephemerides;
- :mod:`.epochs`: epochs and their time scales (TDB unless stated otherwise);
- :mod:`.timing_epochs`: timing-ephemeris epochs as text, ``BJD_TDB …`` at full precision;
- :mod:`.smearing`, :mod:`.binary`, :mod:`.constants`.
"""
