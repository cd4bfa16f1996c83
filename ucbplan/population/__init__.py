"""Whole LISA catalogs: population forecasts, visibility and target selection.

Modules: :mod:`~ucbplan.population.catalog` (LDC-style catalogs from ECSV, CSV, HDF5),
:mod:`~ucbplan.population.catalog_forecast` (per-source Fisher forecast, σ_u, T_valid, SNR),
:mod:`~ucbplan.population.execute` (the executor seam: serial, process pool, Dask; part files,
resume), :mod:`~ucbplan.population.runner` (whole-catalog runs: a job, its run control, the
merged table), :mod:`~ucbplan.population.tables` (what every population table shares: source
columns, blank rows, provenance, status tally, the ECSV writer),
:mod:`~ucbplan.population.plots` (summary figures), :mod:`~ucbplan.population.visibility`
(usable hours, nights and anchor epochs at a site in a semester; semesters and ESO periods come
from :mod:`ucbplan.observing.observatory.semesters`), :mod:`~ucbplan.population.rank` (figures of
merit, target files for the best sources), :mod:`~ucbplan.population.simulate` (the simulate
pipeline per source). Nothing is loaded on package import.
"""

__all__: list[str] = []
