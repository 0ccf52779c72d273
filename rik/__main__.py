"""``python -m rik`` runs the ``rik`` command."""

from rik.cli.app import main

main()
