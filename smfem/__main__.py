"""``python -m smfem``: the command line (docs/contract.md). An entry point, not part of the
solver: nothing imports it, so it may sit above every layer (docs/architecture.md)."""

import sys

from smfem.cli import main

sys.exit(main())
