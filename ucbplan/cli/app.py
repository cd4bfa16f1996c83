"""The ``ucbplan`` command line: a thin shell over the library.

Each command family lives in its own ``ucbplan.cli`` module exposing ``register(app)``; this
module only builds the app, runs each command in the offline astropy scope and turns
``UcbplanError`` into one line on stderr with exit code 2 (no traceback).
"""

from __future__ import annotations

import gc
import os
import sys
from typing import NoReturn

import typer

from ucbplan._version import __version__
from ucbplan.cli._console import err_console
from ucbplan.cli._flags import cli_message
from ucbplan.errors import MAX_VALUE_CHARS, UcbplanError, shorten

app = typer.Typer(
    name="ucbplan",
    help="Phase-targeted spectroscopy of ultracompact binaries from LISA ephemerides.",
    no_args_is_help=True,
    add_completion=True,
    rich_markup_mode=None,  # plain help: rich markup would eat "[deg]"-style units
    pretty_exceptions_enable=False,
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"ucbplan {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    ctx: typer.Context,
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
    debug: bool = typer.Option(
        False, "--debug", help="On an internal error, show the Python traceback (for bug reports)."
    ),
    quiet: bool = typer.Option(
        False, "--quiet", "-q", help="Print only warnings and errors (no tables or notes)."
    ),
) -> None:
    """Run the command inside the offline astropy scope (restored when the command ends)."""
    from ucbplan.api.terminal import offline

    err_console.quiet_info = quiet
    ctx.with_resource(offline())


def _register_all() -> None:
    from ucbplan.cli import (
        core,
        export,
        feasibility,
        lisa,
        now,
        plan,
        population,
        reduce,
        replan,
    )

    for module in (core, plan, replan, now, export, feasibility, reduce, lisa, population):
        module.register(app)


_register_all()


#: Exit codes: 0 success, 1 internal error (a bug: please report), 2 the user's input or
#: environment (one line says what to fix), 130 interrupted (Ctrl-C).
EXIT_OK, EXIT_BUG, EXIT_USER, EXIT_INTERRUPTED = 0, 1, 2, 130

_REPORT = "please report it with the command line and input files (run with --debug for details)"


def _debug_requested(argv: list[str]) -> bool:
    return "--debug" in argv or os.environ.get("UCBPLAN_DEBUG", "") not in ("", "0")


#: Longest error line printed [characters]; longer messages are cut in the middle.
MAX_ERROR_CHARS = 390


def _one_line(text: str) -> str:
    line = " ".join(str(text).split())
    if len(line) <= MAX_ERROR_CHARS:
        return line
    half = MAX_ERROR_CHARS // 2 - 2
    return f"{line[:half]} … {line[-half:]}"


def _fail(message: str, code: int) -> NoReturn:
    # literal text (markup=False): a file name like hmcnc[draft].yaml is printed as it is spelled
    err_console.print(message, soft_wrap=True, markup=False)
    sys.exit(code)


def _os_error(exc: OSError) -> str:
    name = str(exc.filename)
    if len(name) > MAX_VALUE_CHARS:  # a huge path (ENAMETOOLONG) is quoted cut, not in full
        name = shorten(name)
    where = f"{name}: " if exc.filename else ""
    return f"error: {where}{exc.strerror or exc}; check the path and its permissions"


def _usage_line(exc: Exception, message: str) -> str:
    """One line for a click/typer usage error: the message and where to find the options."""
    ctx = getattr(exc, "ctx", None)
    path = getattr(ctx, "command_path", "ucbplan") if ctx is not None else "ucbplan"
    return f"error: {_one_line(message)} (see `{path} --help`)"


def _run() -> int:
    """Run the app in non-standalone mode and return its exit code."""
    code = app(standalone_mode=False)
    return code if isinstance(code, int) else EXIT_OK


def main() -> None:
    """Console-script entry point: one-line errors and exit codes (see :data:`EXIT_USER`).

    User errors (:class:`UcbplanError`, usage errors, unreadable files) print one line and exit 2;
    Ctrl-C exits 130 (commands save what can be saved first); anything else is a bug: one line
    asking for a report, exit 1, and the traceback only with ``--debug`` (or UCBPLAN_DEBUG=1).
    """
    debug = _debug_requested(sys.argv[1:])
    if "--debug" in sys.argv[1:]:
        sys.argv.remove("--debug")
    try:
        code = _run()
    except UcbplanError as exc:
        _fail(f"error: {_one_line(cli_message(str(exc)))}", EXIT_USER)
    except (typer.Exit, SystemExit) as exc:
        code = getattr(exc, "exit_code", getattr(exc, "code", 0))
        code = code if isinstance(code, int) else EXIT_BUG
    except (typer.Abort, KeyboardInterrupt):
        code = EXIT_INTERRUPTED
    except OSError as exc:
        if debug:
            raise
        _fail(_os_error(exc), EXIT_USER)
    except Exception as exc:
        # typer vendors click, so duck-type its ClickException (usage errors: show() + exit_code)
        message, exit_code = getattr(exc, "format_message", None), getattr(exc, "exit_code", None)
        if callable(message) and isinstance(exit_code, int):
            text = str(message()).strip()
            if not text:  # no arguments at all: the help was printed
                sys.exit(exit_code)
            _fail(_usage_line(exc, text), exit_code)
        if debug:
            raise
        _fail(f"internal error: {type(exc).__name__}: {_one_line(str(exc))[:150]}; {_REPORT}", 1)
    if code == EXIT_INTERRUPTED:
        err_console.print("interrupted", markup=False)
    sys.exit(code)


#: How many times rarer the process entry (:func:`run`) makes the collector's full collections.
FULL_COLLECTIONS_RARER = 100


def run() -> None:
    """The process entry point (the ``ucbplan`` console script, ``python -m ucbplan``).

    Runs :func:`main` with the objects the imports made frozen out of the garbage collector
    (:func:`gc.freeze`): they live as long as the process, and a full collection during the
    command would otherwise trace them all again (~0.07 CPU s of a semester plan, issue 34).
    When it exits, the objects the command made are frozen too: the process ends right after,
    and the interpreter's shutdown would otherwise trace them all in several full collections
    (~0.2 CPU s of a one-night plan) to free memory the operating system reclaims anyway. Exit
    code, output, flushing and ``atexit`` handlers are as without it. In-process callers (tests,
    notebooks) call :func:`main`, which leaves the collector alone.

    It also runs OpenBLAS on one thread unless the environment says otherwise
    (``OPENBLAS_NUM_THREADS``, read once when numpy loads, which is after this): ucbplan's
    matrix products are a few columns wide, where a second thread only spins (~0.1 CPU s of a
    semester plan, ~0.05 s of numpy's import), and no result then depends on the thread count.

    The collector stays on, its young generations as they were, but a full collection comes
    :data:`FULL_COLLECTIONS_RARER` times rarer: the imports during a command (astropy, scipy)
    leave hundreds of thousands of long-lived objects that each full collection traces again
    (~0.1 CPU s of a reduce of 10⁶ spectra, ~0.07 s of a semester plan), while the short-lived
    cycles a command makes die young. A long command (a posterior, a population) still gets
    full collections, so its memory stays bounded.
    """
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    young, middle, full = gc.get_threshold()
    gc.set_threshold(young, middle, full * FULL_COLLECTIONS_RARER)
    gc.freeze()
    try:
        main()
    finally:
        gc.freeze()
