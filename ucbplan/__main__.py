"""``python -m ucbplan`` runs the CLI."""

from ucbplan.cli import main

main()
