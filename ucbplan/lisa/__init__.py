"""Reduced small-eccentricity LISA simulation: waveform, response, noise, inference.

Stands apart from the planning pipeline and only *produces* target files (paper Sec. 4.1,
Appendices D and E). Import the submodules directly; nothing is loaded on package import.
"""

__all__: list[str] = []
