"""What a solver process runs: one solve, its stages and its result sent back through a pipe.

Light on purpose: the server imports it to name the target of a solver process, and
only the solver processes import the optimisation stack (the fork server of
:mod:`dashboard.solving` preloads it, so each solver process starts with Pyomo and
HiGHS already imported). It must not import Streamlit.
"""

from __future__ import annotations

import rvpp
from rvpp import Case, CaseError, RvppError


def solve_into(connection, case: Case) -> None:
    """Solve ``case`` and send ``("stage", text)`` messages, then one ``("result", Result)``,
    ``("refused", problems)`` or ``("failed", message)``."""
    try:
        result = rvpp.solve(case, progress=lambda stage: connection.send(("stage", stage)))
        connection.send(("result", result))
    except CaseError as err:
        connection.send(("refused", list(err.problems)))
    except RvppError as err:
        connection.send(("refused", [str(err)]))
    except Exception as exc:  # reported to the page, which shows it in place of the plan
        connection.send(("failed", f"{exc.__class__.__name__}: {exc}"))
    finally:
        connection.close()
