"""Read a solved Pyomo model into the plain tables of a :class:`~rvpp.solving.results.Result`."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pyomo.environ as pyo

from ..data.history import PRICE_COLUMNS
from .problem import Problem
from .results import flexibility_table

SOLVER_ZERO = 1e-9  # solver round-off below this is reported as exactly 0


def _v(component) -> float:
    value = pyo.value(component, exception=False)
    if value is None or abs(value) < SOLVER_ZERO:
        return 0.0
    return float(value)


def extract(m: pyo.ConcreteModel, problem: Problem) -> dict:
    """Read a solved model into plain numbers and tables."""
    case, T = problem.case, list(m.T)
    parts = {
        "revenue_dam_eur": _v(m.revenue_dam),
        "revenue_sr_eur": _v(m.revenue_sr),
        "cost_hpa_eur": _v(m.cost_hpa),
        "cost_opex_eur": _v(m.cost_opex),
    }
    protection = {name: _v(m.protection[name]) for name in PRICE_COLUMNS}
    market = _market_table(m, problem, T)
    units = _units_table(m, problem, T)
    csp = _csp_table(m, problem, T)
    return {"parts": parts, "protection_eur": protection, "market": market, "units": units, "csp": csp,
            "flexibility": flexibility_table(units, case)}


def _period_columns(problem: Problem) -> dict:
    return {"t": np.arange(1, problem.nt + 1), "start": [p.isoformat() for p in problem.periods],
            "clock": problem.labels}


def _market_table(m, problem: Problem, T: list[int]) -> pd.DataFrame:
    da, up, dn = (problem.sources[n] for n in PRICE_COLUMNS)
    return pd.DataFrame({
        **_period_columns(problem),
        "p_da_mw": [_v(m.p_da[t]) for t in T],
        "r_sr_up_mw": [_v(m.r_sr_up[t]) for t in T],
        "r_sr_dn_mw": [_v(m.r_sr_dn[t]) for t in T],
        "h_hpa_mw": [_v(m.h_hpa[t]) for t in T],
        "price_da_mid": da.nominal,
        "price_da_pos": da.deviation_up,
        "price_da_neg": da.deviation,
        "price_sr_up_hi": up.nominal,
        "price_sr_up_neg": up.deviation,
        "price_sr_dn_hi": dn.nominal,
        "price_sr_dn_neg": dn.deviation,
        "tariff_hpa": problem.tariff_hpa,
    })


def _chi(m, name: str, T: list[int]) -> list[float]:
    return [round(_v(m.robust[name].chi[t])) for t in T]


def _units_table(m, problem: Problem, T: list[int]) -> pd.DataFrame:
    rows = []
    base = _period_columns(problem)

    def add(kind, name, p, r_up, r_dn, nominal, deviation, bound, chi):
        rows.append(pd.DataFrame({**base, "unit": name, "kind": kind, "p_mw": p, "r_up_mw": r_up,
                                  "r_dn_mw": r_dn, "nominal_mw": nominal, "deviation_mw": deviation,
                                  "bound_mw": bound, "chi": chi}))

    for kind, unit in problem.case.units():
        name = unit.name
        src = problem.sources[name]
        if kind in ("wind", "pv", "ed"):
            b = m.ndres[name] if kind != "ed" else m.ed[name]
            add(kind, name, [_v(b.p[t]) for t in T], [_v(b.r_up[t]) for t in T], [_v(b.r_dn[t]) for t in T],
                src.nominal, src.deviation, [_v(b.bound[t]) for t in T], _chi(m, name, T))
        elif kind == "td":
            b = m.td[name]
            zeros = np.zeros(len(T))
            add(kind, name, [_v(b.h[t]) for t in T], zeros, zeros, src.nominal, src.deviation,
                [_v(b.bound[t]) for t in T], _chi(m, name, T))
        else:
            b = m.csp[name]
            empty = np.full(len(T), np.nan)
            add(kind, name, [_v(b.e["none", t]) for t in T], [_v(b.r_up[t]) for t in T],
                [_v(b.r_dn[t]) for t in T], empty, empty, empty, empty)
    if not rows:
        return pd.DataFrame()
    table = pd.concat(rows, ignore_index=True)
    table["chi"] = table["chi"].astype("Int64")
    return table


def _csp_table(m, problem: Problem, T: list[int]) -> pd.DataFrame:
    frames = []
    base = _period_columns(problem)
    for csp in problem.case.csp:
        b, src, ts = m.csp[csp.name], problem.sources[csp.name], csp.storage
        span = ts.e_max_mwh_th - ts.e_min_mwh_th
        e = {s: [_v(b.e[s, t]) if s in m.S else _v(b.e["none", t]) for t in T] for s in ("none", "up", "dn")}
        sigma_up, sigma_dn = _v(b.sigma_up), _v(b.sigma_dn)
        frames.append(pd.DataFrame({
            **base, "unit": csp.name,
            "p_sf_mw": [_v(b.p_sf[t]) for t in T],
            "sf_nominal_mw": src.nominal,
            "sf_deviation_mw": src.deviation,
            "sf_bound_mw": [_v(b.bound[t]) for t in T],
            "chi": _chi(m, csp.name, T),
            "p_pb_mw": [_v(b.p_pb[t]) for t in T],
            "e_none_mw": e["none"], "e_up_mw": e["up"], "e_dn_mw": e["dn"],
            "ts_charge_mw": [_v(b.p_ch[t]) for t in T],
            "ts_discharge_mw": [_v(b.p_dis[t]) for t in T],
            "ts_energy_mwh": [_v(b.e_ts[t]) for t in T],
            "ts_r_up_mw": [_v(b.r_ts_up[t]) for t in T],
            "ts_r_dn_mw": [_v(b.r_ts_dn[t]) for t in T],
            "charging": [round(_v(b.charging[t])) for t in T],
            "online": [round(_v(b.online[t])) for t in T],
            "startup": [round(_v(b.startup[t])) for t in T],
            "heat_to_td_mw": [_v(b.h[t]) for t in T],
            "sigma_up": sigma_up, "sigma_dn": sigma_dn,
            "shutdown": [round(_v(b.shutdown[t])) for t in T],
            "ts_r_ch_up_mw": [_v(b.r_ch_up[t]) for t in T],
            "ts_r_ch_dn_mw": [_v(b.r_ch_dn[t]) for t in T],
            "ts_r_dis_up_mw": [_v(b.r_dis_up[t]) for t in T],
            "ts_r_dis_dn_mw": [_v(b.r_dis_dn[t]) for t in T],
            "ts_energy_floor_mwh": ts.e_min_mwh_th + sigma_up * span,
            "ts_energy_ceiling_mwh": ts.e_max_mwh_th - sigma_dn * span,
        }))
    if not frames:
        return pd.DataFrame()
    return pd.concat(frames, ignore_index=True)
