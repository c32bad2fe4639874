"""Subcommands of `vinadv`; each module has `register(subparsers)`."""
