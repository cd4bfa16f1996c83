"""Figures: one place that picks matplotlib's backend and writes figures atomically.

Every plot module gets pyplot from :func:`pyplot` (the non-interactive Agg backend, chosen once,
never on import) and writes through :func:`save_figure`, so a figure file appears whole or not at
all and is never overwritten without ``overwrite=True``.
"""

from __future__ import annotations

from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from ucbplan.errors import InputError, shorten
from ucbplan.io import check_output_path, write_output

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["FIGURE_FORMATS", "check_figure_path", "figure_format", "pyplot", "save_figure"]

#: Figure formats every ``--plot`` writes, chosen by the file's suffix.
FIGURE_FORMATS = ("png", "pdf", "svg")


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the file-only Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def figure_format(path: Path, option: str = "plot") -> str:
    """The format of the figure file ``path`` by its suffix, one of :data:`FIGURE_FORMATS`.

    Raises
    ------
    InputError
        Any other suffix, or none (``--plot figs/`` names a folder, not a figure).
    """
    fmt = path.suffix.lstrip(".").lower()
    if fmt not in FIGURE_FORMATS:
        got = f"got {shorten(path.name, 60)}" if path.name else "got no file name"
        raise InputError(
            f"{option}: expected a .png, .pdf or .svg file name, {got}; "
            f"name the figure e.g. {path.stem or 'figure'}.pdf"
        )
    return fmt


def check_figure_path(path: Path, overwrite: bool, option: str = "plot") -> None:
    """Check a figure path before any work: a known format, an existing folder, and no file
    replaced without ``overwrite``.

    Raises
    ------
    InputError
        As :func:`figure_format`.
    OutputExistsError, OutputError
        As :func:`ucbplan.io.check_output_path`.
    """
    figure_format(path, option)
    check_output_path(path, overwrite)


def save_figure(fig: Figure, path: Path, *, overwrite: bool = False, dpi: int = 120) -> None:
    """Write ``fig`` to ``path`` atomically (format from the suffix: .png, .pdf, .svg) and close it.

    Raises
    ------
    InputError
        If the suffix is not one of :data:`FIGURE_FORMATS`.
    OutputExistsError
        If ``path`` exists and ``overwrite`` is false.
    """
    try:
        fmt = figure_format(path)
    except InputError:
        pyplot().close(fig)
        raise

    def _write(handle: IO[Any]) -> None:
        fig.savefig(handle, format=fmt, dpi=dpi)

    try:
        write_output(path, _write, overwrite=overwrite, binary=True)
    finally:
        pyplot().close(fig)
