"""Output files: one atomic writer, file sets written as a unit, the ``-o`` rule, JSON encoding.

Every file ucbplan writes goes through :func:`write_output` (or :func:`write_file_set` for files
that belong together), so that

- a failed run never leaves a partial or changed file: data go to a temporary file in the same
  folder, which is renamed into place only when the writer finished;
- nothing is overwritten without ``overwrite=True`` (``--overwrite``), and of several concurrent
  runs writing the same new file exactly one succeeds (the file is linked into place, which fails
  when the name exists, instead of checked-then-written);
- only regular files are written: a directory, device or FIFO named as output is refused;
- new files get mode 0666 less the umask (0644 by default), like any file the shell creates;
- a missing or read-only folder or a full disk is one line saying which file and what to do.
"""

from __future__ import annotations

import errno
import json
import math
import os
import stat
import sys
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import IO, Any

from ucbplan.errors import InputError, OutputError, OutputExistsError, shorten

Writer = Callable[[IO[Any]], None]


def _folder(path: Path) -> Path:
    return path.parent if str(path.parent) else Path(".")


def check_output_path(path: Path, overwrite: bool) -> None:
    """Refuse to clobber an existing file unless ``overwrite``; the folder must exist.

    Raises
    ------
    OutputExistsError
        If ``path`` exists and ``overwrite`` is false.
    OutputError
        If ``path`` names something other than a regular file, or its folder does not exist.
    """
    try:
        mode = path.lstat().st_mode
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        raise OutputError(f"{path}: cannot inspect the output path ({exc.strerror})") from None
    if mode is not None:
        if not stat.S_ISREG(mode):
            kind = "a folder" if stat.S_ISDIR(mode) else "not a regular file"
            raise OutputError(f"{path}: output path is {kind}; give a file name with `output`")
        if not overwrite:
            raise OutputExistsError(
                f"{path}: output file exists; pass `overwrite` to replace it or choose another "
                "-o path"
            )
    parent = _folder(path)
    if not parent.is_dir():
        raise OutputError(f"{path}: folder {parent} does not exist; create it first")


def _io_error(path: Path, exc: OSError) -> OutputError:
    """One-line message for an OS error while writing ``path``."""
    if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        why = f"folder {_folder(path)} is not writable; choose another -o path"
    elif exc.errno in (errno.ENOSPC, errno.EDQUOT):
        why = "no space left on the device; free space or write elsewhere"
    elif exc.errno == errno.ENAMETOOLONG:
        why = "file name too long; choose a shorter -o path"
    else:
        why = f"{exc.strerror or exc}; check the path"
    return OutputError(f"{path}: cannot write: {why}")


def _file_mode() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def _write_temp(path: Path, writer: Writer, binary: bool) -> Path:
    """Run ``writer`` into a new temporary file beside ``path``; return the temporary's path."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=_folder(path))
    except OSError as exc:
        raise _io_error(path, exc) from None
    try:
        os.fchmod(fd, _file_mode())
        with os.fdopen(fd, "wb" if binary else "w", encoding=None if binary else "utf-8") as fh:
            writer(fh)
            fh.flush()
            os.fsync(fh.fileno())
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise _io_error(path, exc) from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return Path(tmp)


def _commit(tmp: Path, path: Path, overwrite: bool) -> None:
    """Move the finished temporary into place (exclusive unless ``overwrite``)."""
    try:
        if overwrite:
            check_output_path(path, overwrite=True)
            os.replace(tmp, path)
            return
        try:
            os.link(tmp, path)
        except FileExistsError:
            raise OutputExistsError(
                f"{path}: output file exists (another run wrote it meanwhile?); pass `overwrite` "
                "to replace it or choose another -o path"
            ) from None
        tmp.unlink()
    except OSError as exc:
        if isinstance(exc, OutputError):
            raise
        raise _io_error(path, exc) from None
    finally:
        tmp.unlink(missing_ok=True)


def write_output(
    path: Path | None,
    writer: Writer,
    *,
    overwrite: bool = False,
    binary: bool = False,
) -> None:
    """Write with ``writer(handle)`` to ``path`` atomically, or to stdout when ``path`` is None.

    The file appears only if ``writer`` finished without error: no partial outputs, ever.

    Raises
    ------
    OutputExistsError
        ``path`` exists (or appeared while writing) and ``overwrite`` is false.
    OutputError
        The path is not a regular file, its folder is missing or read-only, or the disk is full.
    """
    if path is None:
        stream = sys.stdout.buffer if binary else sys.stdout
        writer(stream)
        stream.flush()
        return
    write_file_set({path: writer}, overwrite=overwrite, binary=binary)


def write_file_set(
    files: Mapping[Path, Writer], *, overwrite: bool = False, binary: bool = False
) -> None:
    """Write several files that belong together as a unit: all of them or none.

    Every destination is checked first, every file is written to a temporary beside it, and only
    then are they moved into place; if moving one fails, the ones already placed by this call are
    removed again (a file that existed before is never removed).

    Raises
    ------
    OutputExistsError, OutputError
        As :func:`write_output`, before anything is written.
    """
    paths = list(files)
    if len({p.resolve() for p in paths}) != len(paths):
        raise OutputError(f"{paths[0]}: two outputs of one run name the same file; rename one")
    for path in paths:
        check_output_path(path, overwrite)
    temps: dict[Path, Path] = {}
    try:
        for path in paths:
            temps[path] = _write_temp(path, files[path], binary)
        placed: list[Path] = []
        existed = {p for p in paths if p.exists()}
        try:
            for path in paths:
                _commit(temps.pop(path), path, overwrite)
                placed.append(path)
        except BaseException:
            for done in placed:
                if done not in existed:
                    done.unlink(missing_ok=True)
            raise
    finally:
        for tmp in temps.values():
            tmp.unlink(missing_ok=True)


def output_format(
    path: Path | None, fmt: str | None, allowed: tuple[str, ...], default: str
) -> str:
    """The one ``-o`` rule: the format is ``--format``, else the file's suffix, else ``default``.

    A ``--format`` that contradicts a known suffix of ``path`` is an error (``-o x.json
    --format ecsv``); an unknown suffix with no ``--format`` takes ``default``.

    Raises
    ------
    InputError
        ``fmt`` is not in ``allowed``, or contradicts the suffix.
    """
    suffix = path.suffix.lstrip(".").lower() if path is not None else ""
    suffix = {"yml": "yaml", "tex": "latex"}.get(suffix, suffix)
    if fmt is not None and fmt not in allowed:
        raise InputError(f"format: expected one of {', '.join(allowed)}, got {shorten(fmt, 40)}")
    if fmt is None:
        return suffix if suffix in allowed else default
    if suffix in allowed and suffix != fmt and path is not None:
        raise InputError(
            f"-o {path}: the suffix says {suffix} but `format` says {fmt}; make them agree"
        )
    return fmt


def json_default(obj: Any) -> Any:
    """``json.dumps`` fallback for numpy scalars/arrays."""
    import numpy as np

    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return float(obj)
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def json_plain(doc: Any) -> Any:
    """``doc`` as plain JSON values: the one rule that NaN and infinities become ``null``.

    Mappings (keys as text), lists and tuples are walked; numpy scalars and arrays become Python
    numbers and lists. JSON has no NaN or infinity, so a value that is not a finite number (a
    horizon not reached, a column left empty) is written as ``null``, which every JSON reader
    understands, instead of failing half-way through the document.
    """
    import numpy as np

    if isinstance(doc, float):
        return doc if math.isfinite(doc) else None
    if isinstance(doc, str | bool | int) or doc is None:
        return doc
    if isinstance(doc, Mapping):
        return {str(k): json_plain(v) for k, v in doc.items()}
    if isinstance(doc, list | tuple):
        return [json_plain(v) for v in doc]
    if isinstance(doc, np.generic | np.ndarray):
        return json_plain(doc.tolist())
    return doc


def dumps_json(doc: Any, *, indent: int | None = 2) -> str:
    """One JSON document as text (NaN and infinities → ``null``, see :func:`json_plain`)."""
    return json.dumps(json_plain(doc), indent=indent, default=json_default, allow_nan=False)


def dump_json(doc: Any, handle: IO[str]) -> None:
    """Write one JSON document (with trailing newline; NaN and infinities → ``null``)."""
    handle.write(dumps_json(doc))
    handle.write("\n")
