"""``python -m ucbplan`` runs the CLI."""

from ucbplan.cli.app import main

main()
