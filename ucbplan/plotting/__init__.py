"""Figures: one place that picks matplotlib's backend and writes figures atomically.

Every plot module gets pyplot from :func:`pyplot` (the non-interactive Agg backend, chosen once,
never on import) and writes through :func:`save_figure`, so a figure file appears whole or not at
all and is never overwritten without ``overwrite=True``.
"""

from __future__ import annotations

from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from ucbplan.io import write_output

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["pyplot", "save_figure"]


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the file-only Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Figure, path: Path, *, overwrite: bool = False, dpi: int = 120) -> None:
    """Write ``fig`` to ``path`` atomically (format from the suffix: .png, .pdf, .svg) and close it.

    Raises
    ------
    OutputExistsError
        If ``path`` exists and ``overwrite`` is false.
    """
    fmt = path.suffix.lstrip(".").lower() or "png"

    def _write(handle: IO[Any]) -> None:
        fig.savefig(handle, format=fmt, dpi=dpi)

    try:
        write_output(path, _write, overwrite=overwrite, binary=True)
    finally:
        pyplot().close(fig)
