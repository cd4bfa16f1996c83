"""ucbplan: phase-targeted spectroscopy of ultracompact binaries from LISA ephemerides.

The method is that of the paper bundled with the project (see README, "How to cite").
"""

__all__ = ["__version__"]

__version__ = "0.1.0"
