"""The ``mstar`` command that ``pip install`` puts on the PATH: the
command-line program itself (``mstar run``, ``check``, ``sweep``,
``animate`` ...; ``docs/python.md``), with its output and exit codes."""

from __future__ import annotations

import sys
from typing import List, Optional

from ._native import cli_main


def main(argv: Optional[List[str]] = None) -> None:
    """Runs the program with ``argv`` (default: the command line's
    arguments) and exits with its exit code."""
    sys.stdout.flush()
    sys.stderr.flush()
    sys.exit(cli_main(sys.argv[1:] if argv is None else argv))


if __name__ == "__main__":
    main()
