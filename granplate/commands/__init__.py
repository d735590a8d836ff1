"""Command-line subcommands in their own modules (registered through cli.COMMAND_MODULES)."""
