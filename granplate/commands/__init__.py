"""Command-line subcommands in their own modules (registered through cli.COMMAND_MODULES)."""

from __future__ import annotations

import sys
from pathlib import Path


def emit_text(text: str, output: str | None) -> None:
    """Write `text` to the file `output` (and say so), or to standard output when None."""
    if output:
        Path(output).write_text(text)
        print(f"written {output}")
    else:
        sys.stdout.write(text)
