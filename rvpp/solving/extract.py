"""Read a solved Pyomo model into the plain tables of a :class:`~rvpp.solving.results.Result`."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pyomo.environ as pyo

from ..data.history import PRICE_COLUMNS
from ..data.kinds import DISPATCHABLE_KINDS, KINDS, UnitKind
from ..model.blocks import unit_block
from ..data.scenarios import Scenario
from ..uncertainty.problem import Problem
from .results import flexibility_table

SOLVER_ZERO = 1e-9  # solver round-off below this is reported as exactly 0


def _v(component) -> float:
    value = pyo.value(component, exception=False)
    if value is None or abs(value) < SOLVER_ZERO:
        return 0.0
    return float(value)


def _series(component, index) -> np.ndarray:
    """Values of an indexed variable or expression over ``index`` [its unit], round-off set to 0.

    A variable's value is read directly (the costly part of ``pyo.value`` is its checks);
    an expression is evaluated. A variable without a value counts as 0, as in :func:`_v`.
    """
    if component.ctype is pyo.Var:
        values = np.fromiter((component[i].value for i in index), dtype=float, count=len(index))
    else:
        values = np.fromiter((pyo.value(component[i], exception=False) for i in index), dtype=float,
                             count=len(index))
    values[np.isnan(values) | (np.abs(values) < SOLVER_ZERO)] = 0.0
    return values


def _integers(component, index) -> np.ndarray:
    """Values of an indexed binary variable, rounded to whole numbers."""
    return np.rint(_series(component, index)).astype(np.int64)


def extract(m: pyo.ConcreteModel, problem: Problem) -> dict:
    """Read a solved model into plain numbers and tables."""
    case, T = problem.case, list(m.T)
    parts = {
        "revenue_dam_eur": _v(m.revenue_dam),
        "revenue_sr_eur": _v(m.revenue_sr),
        "cost_hpa_eur": _v(m.cost_hpa),
        "cost_opex_eur": _v(m.cost_opex),
        "value_heat_kept_eur": _v(m.value_heat_kept),
    }
    protection = {name: _v(m.protection[name]) for name in PRICE_COLUMNS}
    market = _market_table(m, problem, T)
    units = _units_table(m, problem, T)
    csp = _csp_table(m, problem, T)
    return {"parts": parts, "protection_eur": protection, "market": market, "units": units, "csp": csp,
            "dispatch": _dispatch_table(m, problem, T), "flexibility": flexibility_table(units, case)}


def _period_columns(problem: Problem) -> dict:
    return {"t": np.arange(1, problem.nt + 1), "start": [p.isoformat() for p in problem.periods],
            "clock": problem.labels}


def _market_table(m, problem: Problem, T: list[int]) -> pd.DataFrame:
    da, up, dn = (problem.sources[n] for n in PRICE_COLUMNS)
    return pd.DataFrame({
        **_period_columns(problem),
        "p_da_mw": _series(m.p_da, T),
        "r_sr_up_mw": _series(m.r_sr_up, T),
        "r_sr_dn_mw": _series(m.r_sr_dn, T),
        "h_hpa_mw": _series(m.h_hpa, T),
        "price_da_mid": da.nominal,
        "price_da_pos": da.deviation_up,
        "price_da_neg": da.deviation,
        "price_sr_up_hi": up.nominal,
        "price_sr_up_neg": up.deviation,
        "price_sr_dn_hi": dn.nominal,
        "price_sr_dn_neg": dn.deviation,
        "tariff_hpa": problem.tariff_hpa,
    })


def _chi(m, name: str, T: list[int]) -> np.ndarray:
    return _integers(m.robust[name].chi, T)


def _units_table(m, problem: Problem, T: list[int]) -> pd.DataFrame:
    """One row per unit and period, units in the case's order; built as whole columns."""
    columns = {key: [] for key in ("unit", "kind", "p_mw", "r_up_mw", "r_dn_mw", "nominal_mw", "deviation_mw",
                                   "bound_mw", "chi")}

    def add(kind, name, p, r_up, r_dn, nominal, deviation, bound, chi):
        kind_name = str(kind)  # plain text in the tables, as in case.yaml
        for key, value in zip(columns, (np.full(len(T), name, dtype=object), np.full(len(T), kind_name, dtype=object),
                                        p, r_up, r_dn, nominal, deviation, bound, chi)):
            columns[key].append(np.asarray(value))

    for kind, unit in problem.case.units():
        name = unit.name
        b = unit_block(m, kind, name)
        if KINDS[kind].role is None:  # a certain unit: no band; a battery's p is its net output
            empty = np.full(len(T), np.nan)
            p = _series(b.p_dis, T) - _series(b.p_ch, T) if kind == UnitKind.BATTERY else _series(b.p, T)
            add(kind, name, p, _series(b.r_up, T), _series(b.r_dn, T), empty, empty, empty,
                np.full(len(T), pd.NA, dtype=object))
            continue
        src = problem.sources[name]
        if kind == UnitKind.CSP:
            empty = np.full(len(T), np.nan)
            add(kind, name, _series(b.e, [(Scenario.NONE, t) for t in T]), _series(b.r_up, T),
                _series(b.r_dn, T), empty, empty, empty, np.full(len(T), pd.NA, dtype=object))
        elif kind == UnitKind.TD:
            zeros = np.zeros(len(T))
            add(kind, name, _series(b.h, T), zeros, zeros, src.nominal, src.deviation,
                _series(b.bound, T), _chi(m, name, T))
        else:
            add(kind, name, _series(b.p, T), _series(b.r_up, T), _series(b.r_dn, T),
                src.nominal, src.deviation, _series(b.bound, T), _chi(m, name, T))
    if not columns["unit"]:
        return pd.DataFrame()
    count = len(columns["unit"])
    base = {key: np.tile(np.asarray(value), count) for key, value in _period_columns(problem).items()}
    table = pd.DataFrame({**base, **{key: np.concatenate(parts) for key, parts in columns.items()}})
    table["chi"] = table["chi"].astype("Int64")
    return table


# The dispatch table's columns after the period's, in order, and its whole-number ones.
DISPATCH_FIELDS = ("unit", "kind", "p_mw", "r_up_mw", "r_dn_mw", "charge_mw", "discharge_mw", "energy_mwh", "charging",
                   "r_ch_up_mw", "r_ch_dn_mw", "r_dis_up_mw", "r_dis_dn_mw", "sigma_up", "sigma_dn",
                   "energy_floor_mwh", "energy_ceiling_mwh", "online", "startup", "shutdown")
DISPATCH_STATES = ("charging", "online", "startup", "shutdown")


def _dispatch_table(m, problem: Problem, T: list[int]) -> pd.DataFrame:
    """One row per battery, hydro or biomass unit and period (MODEL_SPEC §13): a battery's charge,
    discharge, energy and reserve by mode with its σ-margins; a hydro or biomass unit's output,
    reserves and commitment. Fields a kind lacks are empty."""
    frames = []
    base = _period_columns(problem)
    empty, missing = np.full(len(T), np.nan), pd.array([pd.NA] * len(T), dtype="Int64")
    for kind, unit in problem.case.units():
        if kind == UnitKind.BATTERY:
            b, span = m.battery[unit.name], unit.e_max_mwh - unit.e_min_mwh
            sigma_up, sigma_dn = _v(b.sigma_up), _v(b.sigma_dn)
            frames.append(pd.DataFrame({
                **base, "unit": unit.name, "kind": str(kind),
                "p_mw": _series(b.p_dis, T) - _series(b.p_ch, T),
                "r_up_mw": _series(b.r_up, T), "r_dn_mw": _series(b.r_dn, T),
                "charge_mw": _series(b.p_ch, T), "discharge_mw": _series(b.p_dis, T),
                "energy_mwh": _series(b.e, T), "charging": _integers(b.charging, T),
                "r_ch_up_mw": _series(b.r_ch_up, T), "r_ch_dn_mw": _series(b.r_ch_dn, T),
                "r_dis_up_mw": _series(b.r_dis_up, T), "r_dis_dn_mw": _series(b.r_dis_dn, T),
                "sigma_up": sigma_up, "sigma_dn": sigma_dn,
                "energy_floor_mwh": unit.e_min_mwh + sigma_up * span,
                "energy_ceiling_mwh": unit.e_max_mwh - sigma_dn * span,
                "online": missing, "startup": missing, "shutdown": missing}))
        elif kind in DISPATCHABLE_KINDS:
            b = m.dispatchable[unit.name]
            frames.append(pd.DataFrame({
                **base, "unit": unit.name, "kind": str(kind),
                "p_mw": _series(b.p, T), "r_up_mw": _series(b.r_up, T), "r_dn_mw": _series(b.r_dn, T),
                "charge_mw": empty, "discharge_mw": empty, "energy_mwh": empty, "charging": missing,
                "r_ch_up_mw": empty, "r_ch_dn_mw": empty, "r_dis_up_mw": empty, "r_dis_dn_mw": empty,
                "sigma_up": empty, "sigma_dn": empty, "energy_floor_mwh": empty, "energy_ceiling_mwh": empty,
                "online": _integers(b.online, T), "startup": _integers(b.startup, T),
                "shutdown": _integers(b.shutdown, T)}))
    if not frames:  # the table's header alone: a workbook sheet or CSV file that says what it would hold
        return pd.DataFrame({column: pd.Series(dtype="Int64" if column in DISPATCH_STATES else float)
                             for column in (*base, *DISPATCH_FIELDS)}).astype({"unit": object, "kind": object})
    table = pd.concat(frames, ignore_index=True)
    return table.astype({column: "Int64" for column in DISPATCH_STATES})


# The CSP table's columns after the period's, in order, and its whole-number ones.
CSP_FIELDS = ("unit", "p_sf_mw", "sf_nominal_mw", "sf_deviation_mw", "sf_bound_mw", "chi", "p_pb_mw", "e_none_mw",
              "e_up_mw", "e_dn_mw", "ts_charge_mw", "ts_discharge_mw", "ts_energy_mwh", "ts_r_up_mw", "ts_r_dn_mw",
              "charging", "online", "startup", "heat_to_td_mw", "sigma_up", "sigma_dn", "shutdown", "ts_r_ch_up_mw",
              "ts_r_ch_dn_mw", "ts_r_dis_up_mw", "ts_r_dis_dn_mw", "ts_energy_floor_mwh", "ts_energy_ceiling_mwh")
CSP_STATES = ("chi", "charging", "online", "startup", "shutdown")


def _csp_table(m, problem: Problem, T: list[int]) -> pd.DataFrame:
    frames = []
    base = _period_columns(problem)
    for csp in problem.case.csp:
        b, src, ts = m.csp[csp.name], problem.sources[csp.name], csp.storage
        span = ts.e_max_mwh_th - ts.e_min_mwh_th
        e = {s: _series(b.e, [(s if s in m.S else Scenario.NONE, t) for t in T]) for s in Scenario}
        sigma_up, sigma_dn = _v(b.sigma_up), _v(b.sigma_dn)
        frames.append(pd.DataFrame({
            **base, "unit": csp.name,
            "p_sf_mw": _series(b.p_sf, T),
            "sf_nominal_mw": src.nominal,
            "sf_deviation_mw": src.deviation,
            "sf_bound_mw": _series(b.bound, T),
            "chi": _chi(m, csp.name, T),
            "p_pb_mw": _series(b.p_pb, T),
            "e_none_mw": e[Scenario.NONE], "e_up_mw": e[Scenario.UP], "e_dn_mw": e[Scenario.DN],
            "ts_charge_mw": _series(b.p_ch, T),
            "ts_discharge_mw": _series(b.p_dis, T),
            "ts_energy_mwh": _series(b.e_ts, T),
            "ts_r_up_mw": _series(b.r_ts_up, T),
            "ts_r_dn_mw": _series(b.r_ts_dn, T),
            "charging": _integers(b.charging, T),
            "online": _integers(b.online, T),
            "startup": _integers(b.startup, T),
            "heat_to_td_mw": _series(b.h, T),
            "sigma_up": sigma_up, "sigma_dn": sigma_dn,
            "shutdown": _integers(b.shutdown, T),
            "ts_r_ch_up_mw": _series(b.r_ch_up, T),
            "ts_r_ch_dn_mw": _series(b.r_ch_dn, T),
            "ts_r_dis_up_mw": _series(b.r_dis_up, T),
            "ts_r_dis_dn_mw": _series(b.r_dis_dn, T),
            "ts_energy_floor_mwh": ts.e_min_mwh_th + sigma_up * span,
            "ts_energy_ceiling_mwh": ts.e_max_mwh_th - sigma_dn * span,
        }))
    if not frames:  # no CSP in the plan: the table's header alone, as the dispatch table's
        return pd.DataFrame({column: pd.Series(dtype=int if column in CSP_STATES else float)
                             for column in (*base, *CSP_FIELDS)}).astype({"start": object, "clock": object,
                                                                           "unit": object})
    return pd.concat(frames, ignore_index=True)


def extract_session(m: pyo.ConcreteModel, problem: Problem) -> dict:
    """Read a solved intraday session (:mod:`rvpp.model.session`) into plain numbers and tables.

    Its ``market`` table is the day-ahead one with the cleared bids, the price columns of the
    session's price (``price_da_*`` hold the intraday price band) and two more columns:
    ``traded_mw`` (the session's trade ``q_k``) and ``position_mw`` (``p_da + Σ_{j≤k} q_j``).
    """
    T = list(m.T)
    parts = {"revenue_intraday_eur": _v(m.revenue_intraday), "protection_intraday_eur": _v(m.protection["price_da"]),
             "cost_opex_eur": _v(m.cost_opex), "value_heat_kept_eur": _v(m.value_heat_kept),
             "cost_heat_short_eur": _v(m.cost_heat_short)}
    market = _market_table(m, problem, T)
    market["traded_mw"] = _series(m.q_id, T)
    market["position_mw"] = _series(m.position, T)
    market["heat_short_mw"] = _series(m.heat_short, T)
    return {"parts": parts, "market": market, "units": _units_table(m, problem, T), "csp": _csp_table(m, problem, T),
            "dispatch": _dispatch_table(m, problem, T)}
