"""The ``ucbplan`` command line: thin shells over the library (parse, call, print).

``main`` is the process entry point (:func:`ucbplan.cli.app.run`: the console script and
``python -m ucbplan``); tests and notebooks, which run the command line inside a process that
goes on, call :func:`ucbplan.cli.app.main`.
"""

from ucbplan.cli.app import run as main

__all__ = ["main"]
