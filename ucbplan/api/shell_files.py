"""The few file checks the command-line shells of ``reduce``, ``simulate``, ``fisher``,
``waveform`` and ``population`` need before any work, so that they import only the API.

Each is a thin, light (lazily importing) door onto the library's one implementation.
"""

from __future__ import annotations

from pathlib import Path


def file_format(path: str | Path, default: str = "yaml") -> str:
    """The format a file's suffix names (``yaml``, ``json``, ``ecsv``, ``csv``), else
    ``default`` (:func:`ucbplan.io.output_format`)."""
    from ucbplan.io import output_format

    return str(output_format(Path(path), None, ("yaml", "json", "ecsv", "csv"), default))


def check_figure_path(path: str | Path, overwrite: bool = False) -> None:
    """Refuse a figure path that exists (without ``overwrite``) or names no image format.

    Raises
    ------
    OutputExistsError, OutputError
        As :func:`ucbplan.plotting.check_figure_path`.
    """
    from ucbplan.plotting import check_figure_path as _check

    _check(Path(path), overwrite)
