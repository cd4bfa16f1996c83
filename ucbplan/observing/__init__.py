"""Observing: from barycentric epochs to blocks of UTC at a real observatory.

Modules, in data-flow order: ``sites`` (bundled observatory table), ``timeconv`` (barycentric TDB
<-> UTC at the site), ``smearing`` (Appendix B attenuation factors), ``constraints`` (night,
altitude, Moon), ``blocks`` (exposure plan around an anchor epoch), ``schedule`` (modes and the
night schedule), ``table`` (the master blocks table every export reads) and ``nightplot``.
Nothing is imported here so that ``import ucbplan.observing`` stays cheap.
"""

__all__: list[str] = []
