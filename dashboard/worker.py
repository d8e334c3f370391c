"""What a solver process runs: one solve (or one sweep of Γ), its stages and its result sent
back through a pipe.

Light on purpose: the server imports it to name the target of a solver process, and
only the solver processes import the optimisation stack (the fork server of
:mod:`dashboard.solving` preloads it, so each solver process starts with Pyomo and
HiGHS already imported). It must not import Streamlit.
"""

from __future__ import annotations

from collections.abc import Callable

import rvpp
from rvpp import Case, CaseError, RvppError


def solve_into(connection, case: Case, stop) -> None:
    """Solve ``case`` and send ``("stage", text)`` and ``("search", Search)`` messages (the
    solver's search every quarter second), then one ``("result", Result)``, ``("refused",
    problems)`` or ``("failed", message)``. Once the event ``stop`` is set, the search ends at its
    best plan (status ``stopped``)."""
    def watch(search) -> bool:
        connection.send(("search", search))
        return stop.is_set()

    _answer(connection, lambda: rvpp.solve(case, progress=lambda stage: connection.send(("stage", stage)),
                                           watch=watch))


def sweep_into(connection, case: Case, gammas: list[int]) -> None:
    """Solve ``case`` for every Γ of ``gammas`` (the same Γ for every source, one model
    re-solved in place) and send ``("progress", (done, total))`` messages, then one
    ``("result", [Result, ...])`` in the order of ``gammas``, or the refusal or failure."""
    from rvpp.service import sweep_gamma  # heavy: the optimisation stack, in solver processes only

    _answer(connection, lambda: sweep_gamma(
        case, gammas, progress=lambda done, total: connection.send(("progress", (done, total)))))


def _answer(connection, work: Callable[[], object]) -> None:
    """Run ``work`` and send its result, or why it has none, then close ``connection``."""
    try:
        connection.send(("result", work()))
    except CaseError as err:
        connection.send(("refused", list(err.problems)))
    except RvppError as err:
        connection.send(("refused", [str(err)]))
    except Exception as exc:  # reported to the page, which shows it in place of the plan
        connection.send(("failed", f"{exc.__class__.__name__}: {exc}"))
    finally:
        connection.close()
