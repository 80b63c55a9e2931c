"""One module per CLI subcommand; each defines `register(subparsers)`.

A command module adds its parser and sets `func=run` where `run(args) -> int`
returns the exit status (see rapidfix.cli for the meaning of the codes).
"""
