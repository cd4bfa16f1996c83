"""The ``ucbplan`` command line: a thin shell over the library.

Each command family lives in its own ``ucbplan.cli`` module exposing ``register(app)``; this
module only builds the app, configures astropy for offline use and turns ``UcbplanError`` into
one line on stderr with exit code 2 (no traceback).
"""

from __future__ import annotations

import sys

import typer

from ucbplan import __version__
from ucbplan.cli._console import configure_offline, err_console
from ucbplan.errors import UcbplanError

__all__ = ["app", "main"]

app = typer.Typer(
    name="ucbplan",
    help="Phase-targeted spectroscopy of ultracompact binaries from LISA ephemerides.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"ucbplan {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """Configure offline astropy once, before any command runs."""
    configure_offline()


def _register_all() -> None:
    from ucbplan.cli import core, export, feasibility, lisa, plan, reduce

    for module in (core, plan, export, feasibility, reduce, lisa):
        module.register(app)


_register_all()


def main() -> None:
    """Console-script entry point: run the app, one-line errors, exit code 2 on user errors."""
    try:
        app(standalone_mode=False)
    except UcbplanError as exc:
        err_console.print(f"[bold red]error:[/] {exc}", soft_wrap=True)
        sys.exit(2)
    except (typer.Exit, SystemExit) as exc:
        code = getattr(exc, "exit_code", getattr(exc, "code", 0))
        sys.exit(code if isinstance(code, int) else 1)
    except typer.Abort:
        err_console.print("aborted")
        sys.exit(130)
    except KeyboardInterrupt:
        err_console.print("interrupted")
        sys.exit(130)
    except Exception as exc:  # click/typer usage errors arrive here in non-standalone mode
        # typer vendors click, so duck-type its ClickException (show() + exit_code)
        show, code = getattr(exc, "show", None), getattr(exc, "exit_code", None)
        if callable(show) and isinstance(code, int):
            show()
            sys.exit(code)
        raise
