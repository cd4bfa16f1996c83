"""The package version, declared once (``ucbplan.__version__`` re-exports it)."""

__version__ = "0.1.0"
