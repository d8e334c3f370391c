"""Plans side by side: the paper's comparison tables.

The plans compared are variants of one case made with :class:`rvpp.data.variants.Variant`.

* :func:`cost_table` — cost [kEUR] per strategy and market set (paper Table 10 layout);
* :func:`flexibility_table` — reserve energy per strategy and unit kind (paper Table 9 layout);
* :func:`kpi_table` — headline numbers of any labelled plans.
"""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from ..data.case import STRATEGIES
from ..data.kinds import UnitKind
from ..solving.results import Result

MARKET_SETS = ("DAM", "DAM+HPA", "DAM+SRM", "DAM+SRM+HPA")  # the columns of the paper's Table 10
# The rows of the paper's Table 9.
KIND_NAMES = {UnitKind.WIND: "WFs", UnitKind.PV: "PVs", UnitKind.CSP: "CSP", UnitKind.ED: "EDs"}
PERCENT = 100.0
KILO = 1000.0
PERCENT_BASE_SHARE = 0.05  # a percentage needs a base of at least 5 % of the gross money flows


def cost_table(results: Mapping[tuple[str, str], Result]) -> pd.DataFrame:
    """Cost [kEUR] (−profit) with one row per strategy and one column per market set.

    ``results`` maps ``(strategy, market set)`` to a result; plans that were not solved
    to a plan are NaN. A strategy other than the presets (e.g. a recommended Γ) is a row
    of its own after them, named as given.
    """
    presets = [s for s in STRATEGIES if any(k[0] == s for k in results)]
    others = list(dict.fromkeys(k[0] for k in results if k[0] not in STRATEGIES))
    sets = [m for m in MARKET_SETS if any(k[1] == m for k in results)]
    table = pd.DataFrame(index=pd.Index([_row(s) for s in presets + others], name="Strategy"),
                         columns=pd.Index(sets, name="Market (contract)"), dtype=float)
    for (strategy, market_set), result in results.items():
        table.loc[_row(strategy), market_set] = result.cost_keur if result.has_plan else float("nan")
    return table


def _row(strategy: str) -> str:
    return strategy.capitalize() if strategy in STRATEGIES else strategy


def flexibility_table(results: Mapping[str, Result]) -> pd.DataFrame:
    """Reserve energy [MWh] and reserve-to-capacity ratio [h] per plan and unit kind."""
    frames = []
    for label, result in results.items():
        if not result.has_plan:
            continue
        flex = result.flexibility
        frames.append(pd.DataFrame({
            "Strategy": label.capitalize() if label in STRATEGIES else label,
            "Unit": flex["kind"].map(KIND_NAMES),
            "Upward reserve [MWh]": flex["r_up_mwh"],
            "Downward reserve [MWh]": flex["r_dn_mwh"],
            "Upward reserve to capacity [h]": flex["r_up_h"],
            "Downward reserve to capacity [h]": flex["r_dn_h"],
        }))
    if not frames:
        return pd.DataFrame()
    return pd.concat(frames, ignore_index=True).set_index(["Strategy", "Unit"])


def kpi_table(results: Mapping[str, Result], baseline: str | None = None) -> pd.DataFrame:
    """One row per labelled plan: status, net cost (positive when the plant pays) and its
    parts [kEUR], solve time [s].

    With ``baseline`` (a label of ``results`` with a plan), each plan's extra cost over
    the baseline [kEUR], positive when the plan costs more: what being safer costs. The
    same in [%] only when the baseline's net cost is at least :data:`PERCENT_BASE_SHARE`
    of its gross money flows (revenues plus costs): a percentage of a near-zero base says
    nothing.
    """
    rows = []
    for label, result in results.items():
        parts = result.parts
        money = {
            "Net cost [kEUR]": None if result.objective_eur is None else -result.objective_eur,
            "DAM revenue [kEUR]": parts.get("revenue_dam_eur"),
            "SR revenue [kEUR]": parts.get("revenue_sr_eur"),
            "HPA cost [kEUR]": parts.get("cost_hpa_eur"),
            "Operating cost [kEUR]": parts.get("cost_opex_eur"),
            "Robust protection [kEUR]": sum(result.protection_eur.values()) if result.protection_eur else None,
        }
        rows.append({"Run": label, "Status": str(result.status),
                     **{k: None if v is None else v / KILO for k, v in money.items()},
                     "Solve time [s]": result.build_s + result.solve_s + result.extract_s})
    table = pd.DataFrame(rows).set_index("Run")
    if baseline is not None and results[baseline].has_plan:
        base = results[baseline]
        extra = table["Net cost [kEUR]"].astype(float) + base.objective_eur / KILO
        table.insert(2, f"Extra cost vs {baseline} [kEUR]", extra)
        if abs(base.objective_eur) >= PERCENT_BASE_SHARE * gross_eur(base):
            table.insert(3, f"Extra cost vs {baseline} [%]", PERCENT * extra * KILO / abs(base.objective_eur))
    return table


def gross_eur(result: Result) -> float:
    """A plan's gross money flows [EUR]: every revenue and cost counted positive."""
    return sum(abs(v) for v in result.parts.values()) + sum(abs(v) for v in result.protection_eur.values())
