"""The ``spectral-skin`` command that ``pip install`` puts on PATH: the core's command line (the same program as
``cargo build --bin spectral-skin``), run in this Python process. ``spectral-skin --help`` lists its subcommands;
docs/cli.md describes them."""

from __future__ import annotations

import sys

from ._core import _cli_main


def main() -> None:
    """Run the command line on ``sys.argv`` and exit with its status (0; 2 for an error; 130 after Ctrl-C)."""
    sys.exit(_cli_main(sys.argv))


if __name__ == "__main__":
    main()
