"""Observing: from barycentric epochs to blocks of UTC at a real observatory.

Modules, in data-flow order: ``sites`` (bundled observatory table), ``barycentric_time``
(barycentric TDB <-> UTC at the site), ``site_time_axis`` (the one inner time representation:
TDB seconds after one epoch), ``sky`` (fast Sun/Moon/target geometry), ``constraints`` (night,
airmass, Moon ... by name) and ``constraint_checks`` (whole blocks against a set), ``blocks``
(exposure plan around an anchor epoch), ``schedule`` (modes, candidates, placement, fixed-u
pairs: the night schedule), ``accounting`` (time accounting of a plan); the master blocks table
every export reads: ``blocktable`` (its columns declared once), ``tableformat`` (its time and
coordinate text, the one sexagesimal formatter), ``tablemake`` (blocks → table, provenance),
``tablewrite`` and ``ecsvheader`` (ECSV, CSV, JSON), ``tableread`` (reading and checking);
``exports`` (observatory formats), ``instruments`` and ``goals`` (overheads, σ_v per exposure,
spectra a precision needs), ``sigma_model`` and ``strategy`` (information per hour),
``semesters``, ``nightplot`` and ``nightsheet`` with ``sheet_html`` (charts and the telescope's
night sheet), ``countdown`` (every exposure of a plan and what is next at an instant:
``ucbplan now``) and ``astroplan_bridge``.
Nothing is imported here so that ``import ucbplan.observing`` stays cheap.
"""

__all__: list[str] = []
