"""rvpp: robust day-ahead bids for a renewable-only virtual power plant.

Typical use::

    import rvpp
    case = rvpp.load_case("data/cases/paper")
    result = rvpp.solve(rvpp.with_options(case, strategy="pessimistic"))
    print(result.status, result.objective_eur)
    rvpp.write_plan(result, "out")

Names are imported on first use, so ``import rvpp`` stays light: the case model and
its validation load without the optimisation stack (Pyomo, HiGHS).
"""

from .lazy import lazy_names

_EXPORTS = {
    "Case": ".data.case", "load_case": ".data.case_yaml", "save_case": ".data.case_yaml", "with_options": ".data.variants",
    "CaseError": ".errors", "ModelError": ".errors", "RvppError": ".errors",
    "Problem": ".uncertainty.problem", "prepare": ".uncertainty.problem",
    "Result": ".solving.results", "Search": ".solving.outcome",
    "audit_export": ".settle.audit", "audit_result": ".settle.audit",
    "write_plan": ".outputs.export",
    "solve": ".solving.plan", "solve_problem": ".solving.plan",
}

__all__ = sorted(_EXPORTS)
__version__ = "0.1.0"


__getattr__, __dir__ = lazy_names(__name__, _EXPORTS)
