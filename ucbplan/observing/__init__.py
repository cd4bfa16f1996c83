"""Observing: from barycentric epochs to blocks of UTC at a real observatory.

One sub-package per concern, in data-flow order: ``observatory`` (sites, their sky, barycentric
TDB <-> UTC at the site, the plan's inner time axis, semesters), ``constraints`` (night, airmass,
Moon ... by name, and whole blocks checked against a set), ``precision`` (instruments, the σ_v
law, information per telescope hour, goals, the spectra already observed), ``blocks`` (the
master blocks table every export reads: blocks, columns declared once, made, formatted, written,
read back, accounted), ``schedule`` (modes, candidates, placement, visits: the night schedule),
``night`` (charts, the telescope's night sheet, the countdown of ``ucbplan now`` and the
observing log) and ``exports`` (observatory and proposal formats, astroplan's Schedule).
Nothing is imported here so that ``import ucbplan.observing`` stays cheap.
"""

__all__: list[str] = []
