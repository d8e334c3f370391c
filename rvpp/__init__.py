"""rvpp: robust day-ahead bids for a renewable-only virtual power plant.

Typical use::

    import rvpp
    case = rvpp.load_case("data/cases/paper")
    result = rvpp.solve(rvpp.with_options(case, strategy="pessimistic"))
    print(result.status, result.objective_eur)
    rvpp.write_plan(result, "out")
"""

from .audit import audit_export, audit_result
from .case import Case, load_case, save_case, with_options
from .errors import CaseError, ModelError, RvppError
from .export import write_plan
from .problem import Problem, prepare
from .results import Result
from .solve import solve, solve_problem

__all__ = [
    "Case", "CaseError", "ModelError", "Problem", "Result", "RvppError", "audit_export", "audit_result",
    "load_case", "prepare", "save_case", "solve", "solve_problem", "with_options", "write_plan",
]
__version__ = "0.1.0"
