"""``python -m op2motion``: the command-line interface."""

from op2motion.cli import entry

entry()
