"""The ``ucbplan`` command line: thin shells over the library (parse, call, print)."""

from ucbplan.cli.app import main

__all__ = ["main"]
