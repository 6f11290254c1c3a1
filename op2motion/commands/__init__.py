"""The command-line subcommands, one module per concept; each calls library functions."""
