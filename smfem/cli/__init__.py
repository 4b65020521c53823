"""The ``smfem`` command line (docs/contract.md): one module per subcommand.

User mistakes end with one line on stderr and exit status 2; a run that fails to converge ends
with exit status 3 after writing the history up to the last converged step.
"""

from __future__ import annotations

import os
import sys

from cases import ParameterError, UnsupportedCase
from smfem.runs import threads

from . import cases_cmd, compare, export, run, study, truth, verify
from .usage import EXIT_USAGE, Parser, UsageError

SUBCOMMANDS = (cases_cmd, run, export, compare, study, truth, verify)


def build_parser() -> Parser:
    p = Parser(prog="smfem", description="Semi-analytic FEM for transient dynamics, verified against scikit-fem.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    for module in SUBCOMMANDS:
        module.add(sub)
    return p


def main(argv=None) -> int:
    threads.pin()
    try:
        args = build_parser().parse_args(argv)
        return args.handler(args)
    except (UsageError, ParameterError, UnsupportedCase) as exc:
        print(f"smfem: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except MemoryError:
        print("smfem: error: out of memory: the model is too large for this machine (lower refine or harmonics)",
              file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # the reader went away (`smfem cases | head`): not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit
        return 0


if __name__ == "__main__":
    sys.exit(main())
