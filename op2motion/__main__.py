"""``python -m op2motion``: the command-line interface."""

from .cli import main

raise SystemExit(main())
