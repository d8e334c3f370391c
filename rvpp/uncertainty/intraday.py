"""What an intraday session knows at its gate closure: forecasts, bands, prices, budgets (MODEL_SPEC §14).

Forecasts. Where the history holds a column ``<forecast_series>_<session>`` (e.g.
``wind_fc_ida2``) for a unit, it is the unit's forecast issued for that session and its band
is the day-ahead band moved to it, the width scaled by the lead-time factor ``s`` below:
``x_k = f_k + s·(x_da − mid_da)`` for ``x`` in lo, mid, hi. Otherwise the forecast is
*modelled*: the day-ahead error shrinks with the lead time,

    ``x_k = actual + (x_da − actual)·s``,   ``s = (L_k / L_da)^exponent``   (clipped to [0, 1]),

for the band's lo, mid and hi alike (so the point forecast ``f_k = actual + (f_da − actual)·s``
and the band width shrink by the same factor). ``L_k`` is the time from the session's gate
closure to the start of the period, ``L_da`` the time from the day-ahead gate
(``reference_gate_closure`` on D-1, 12:00 by default) to it; ``exponent`` is
``lead_time_exponent`` (0.5: the error's spread grows as the square root of the lead time, as
for a random walk). The model uses the realized value of the day: it is a stand-in for a
forecast that a real operator would have had, whose error is the day-ahead error made smaller,
never a forecast of anything else; the session still plans against the band, not the actual.

Prices. The day-ahead prices of D are cleared (about 13:00 on D-1) before the first session, so
every session knows them. The session's price forecast is that day-ahead price, ``λ~_k = λ_da``;
its band is ``λ_da ± σ·z`` with ``σ = price_spread_eur_per_mwh`` and ``z`` the standard normal
quantile of ``uncertainty.q_hi``, protected like the DAM price (§4) on the trade. The realized
intraday price is the history's column ``price_<session>`` (e.g. ``price_ida2``) where present,
otherwise *modelled*: ``λ_k = λ_da + σ·ε``, ``ε`` standard normal, drawn by numpy's PCG64 from
the seed ``(price_seed, ordinal of D, session number)``; a session never sees its ``ε``.

Outside the session's window the bands are those the step before planned with, at zero width,
so the periods already locked keep what they were planned for. Budgets: ``Γ_k = ⌊Γ_da·f_k·|W_k|
/ NT + ½⌋`` per source with ``f_k`` the session's factor (:meth:`IntradaySettings.gamma_factor`).
"""

from __future__ import annotations

import dataclasses
from statistics import NormalDist

import numpy as np
import pandas as pd

from ..data.case import Case
from ..data.intraday import SessionTime, reference_gate, session_gamma
from ..data.intraday import forecast_column as session_forecast_column, price_column as session_price_column
from ..errors import CaseError
from .bands import realized_values
from .forecast import band_specs
from .problem import Problem, problem_from_bands

MODELLED, REAL = "modelled", "real"


def lead_factor(periods: pd.DatetimeIndex, gate: pd.Timestamp, reference: pd.Timestamp, exponent: float) -> np.ndarray:
    """``s = (L_k / L_da)^exponent`` per period, clipped to [0, 1] (1 where the period starts before the gate)."""
    lead = np.asarray((periods - gate) / pd.Timedelta(hours=1), dtype=float)
    lead_da = np.asarray((periods - reference) / pd.Timedelta(hours=1), dtype=float)
    ratio = np.where(lead_da > 0.0, np.clip(lead, 0.0, None) / np.where(lead_da > 0.0, lead_da, 1.0), 1.0)
    factor = np.where(lead > 0.0, ratio, 0.0) ** exponent if exponent > 0 else np.ones_like(ratio)
    return np.where(lead >= 0.0, np.clip(factor, 0.0, 1.0), 1.0)


def price_column(session: SessionTime) -> str:
    return session_price_column(session.name)


def forecast_column(base: str, session: SessionTime) -> str:
    return session_forecast_column(base, session.name)


def _day_column(case: Case, day, periods: pd.DatetimeIndex, column: str, scale: float = 1.0,
                limits: tuple | None = None) -> np.ndarray:
    values = realized_values(case.history, day, periods, {"x": (column, scale)}, case.timezone,
                             {"x": limits} if limits else None)["x"].to_numpy(float)
    if not np.isfinite(values).all():
        t = int(np.flatnonzero(~np.isfinite(values))[0])
        raise CaseError(f"history column {column!r} has no value for {periods[t]} of {day}; the intraday "
                        "session needs one per period")
    return values


def realized_price(case: Case, session: SessionTime, periods: pd.DatetimeIndex, price_da: np.ndarray
                   ) -> tuple[np.ndarray, str]:
    """The intraday price the session's trades settle at [EUR/MWh] and its origin (real or modelled)."""
    column = price_column(session)
    if column in case.history.columns:
        return _day_column(case, case.delivery_date, periods, column), REAL
    settings = case.intraday
    rng = np.random.default_rng([settings.price_seed, case.delivery_date.toordinal(), session.index])
    return np.asarray(price_da, dtype=float) + settings.price_spread_eur_per_mwh * rng.standard_normal(len(periods)), \
        MODELLED


def session_problem(case: Case, day_ahead: Problem, previous: Problem, session: SessionTime,
                    actual: pd.DataFrame) -> tuple[Problem, dict[str, str]]:
    """The :class:`Problem` of ``session`` and the origin of each band (``real`` or ``modelled``).

    ``day_ahead``: the day-ahead problem (its bands are the base the error model shrinks);
    ``previous``: the problem of the step before (day-ahead or the previous session), whose
    nominal values the periods before the window keep; ``actual``: the realized values of the
    day per source (the day-ahead price among them).
    """
    settings, periods = case.intraday, day_ahead.periods
    first = session.first
    factor = lead_factor(periods, session.gate, reference_gate(settings, case.delivery_date, case.timezone),
                         settings.lead_time_exponent)
    bands = day_ahead.bands.copy()
    origin: dict[str, str] = {}
    specs = band_specs(case)
    for kind, unit in case.uncertain_units():
        name, spec = unit.name, specs[unit.name]
        lo, mid, hi = (day_ahead.bands[(name, stat)].to_numpy(float) for stat in ("lo", "mid", "hi"))
        own = forecast_column(spec.forecast_column, session) if spec.forecast_column else None
        if own is not None and own in case.history.columns:
            point = _day_column(case, case.delivery_date, periods, own, spec.scale, (spec.low, spec.high))
            anchor, origin[name] = mid, REAL
        else:
            point = anchor = actual[name].to_numpy(float)
            origin[name] = MODELLED
        for stat, x in (("lo", lo), ("mid", mid), ("hi", hi)):
            bands[(name, stat)] = point + factor * (x - anchor)
    price_da = actual["price_da"].to_numpy(float)
    half = case.intraday.price_spread_eur_per_mwh * NormalDist().inv_cdf(case.uncertainty.q_hi)
    for stat, x in (("lo", price_da - half), ("mid", price_da), ("hi", price_da + half)):
        bands[("price_da", stat)] = x
    origin["price"] = REAL if price_column(session) in case.history.columns else MODELLED
    for name, source in previous.sources.items():  # the periods before the window keep the step before's values
        for stat in ("lo", "mid", "hi"):
            bands.loc[bands.index[:first], (name, stat)] = source.nominal[:first]
    problem = problem_from_bands(case, periods, bands)
    window, gamma_factor = len(periods) - first, settings.gamma_factor(session.index)
    sources = {name: dataclasses.replace(source, gamma=session_gamma(day_ahead.sources[name].gamma, gamma_factor,
                                                                       window, len(periods)))
               for name, source in problem.sources.items()}
    return dataclasses.replace(problem, sources=sources), origin
