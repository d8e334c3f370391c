"""Command line: ``python -m rvpp solve|data|study ...``.

Every failure ends with exit code 1 and one line ``error: ...`` that names the option,
file or field and the rule, never a traceback: a bad option, a case that breaks a rule,
a file that cannot be read or written, and a solve without a plan (infeasible, solver
error). Success exits with 0.

During ``solve``, Ctrl-C ends the solver's search with the best plan found so far, which
is written as usual with status ``stopped`` and its gap (exit code 0); a second Ctrl-C
gives up the solve (exit code 130, nothing written). A long search reports itself every
:data:`SEARCH_REPORT_S` seconds.
"""

from __future__ import annotations

import argparse
import sys

from ..errors import RvppError
from .backtest import add_backtest_commands
from .data import add_data_commands
from .options import FAILURE, INTERRUPTED, Parser
from .solve import add_solve_command
from .studies import add_study_commands


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help (0) or a bad option (1, message already printed)
        return exc.code if isinstance(exc.code, int) else FAILURE
    if not hasattr(args, "run"):
        parser.print_help(sys.stderr)
        return FAILURE
    try:
        return args.run(args)
    except KeyboardInterrupt:
        print("error: interrupted; nothing more was written", file=sys.stderr)
        return INTERRUPTED
    except RvppError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return FAILURE
    except OSError as exc:  # writing the outputs: a full disk, no permission, a file where a folder belongs
        where = f": {exc.filename}" if exc.filename else ""
        print(f"error: cannot write{where} ({exc.strerror or exc})", file=sys.stderr)
        return FAILURE


def _parser() -> argparse.ArgumentParser:
    parser = Parser(prog="python -m rvpp", description=(
        "Robust day-ahead bids for a renewable-only virtual power plant (DAM, aFRR reserve, heat purchase)."))
    commands = parser.add_subparsers(title="commands")
    add_solve_command(commands)
    add_data_commands(commands)
    add_study_commands(commands)
    add_backtest_commands(commands)
    return parser


