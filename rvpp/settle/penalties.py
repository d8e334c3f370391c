"""The settlement's penalty settings (MODEL_SPEC §10), apart from the recourse model, so that
the command line and the settings of backtests and studies read them without the solver stack."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..data.case import Case
from ..data.history import MAX_QUANTITY
from ..errors import SettlementError

HEAT_PRICE_FACTOR = 2.0  # default c_heat = 2 × the highest HPA tariff (MODEL_SPEC §10)


@dataclass(frozen=True)
class Penalties:
    """Penalty settings of the settlement (MODEL_SPEC §10), all editable.

    ``m_def`` and ``m_sur`` set the imbalance prices from the realized DAM price λ
    [EUR/MWh]: a deficit is bought back at ``π_def = λ + (m_def − 1)·|λ|`` and a surplus
    sold at ``π_sur = λ − (1 − m_sur)·|λ|``, so ``m_def ≥ 1`` and ``0 ≤ m_sur ≤ 1`` make
    either imbalance cost money whatever the sign of λ. ``m_sr`` multiplies the realized SR
    prices of undelivered reserve [-]; ``c_heat_eur_per_mwh`` prices unserved heat
    [EUR/MWh_th] (``None``: twice the highest HPA tariff of the case).
    """

    m_def: float = 2.0
    m_sur: float = 0.5
    m_sr: float = 2.0
    c_heat_eur_per_mwh: float | None = None

    def __post_init__(self) -> None:
        for name in ("m_def", "m_sur", "m_sr", "c_heat_eur_per_mwh"):
            value = getattr(self, name)
            if value is not None and not (isinstance(value, (int, float)) and np.isfinite(value)):
                raise SettlementError(f"penalties: {name}={value} must be a finite number")
            if value is not None and value > MAX_QUANTITY:
                raise SettlementError(f"penalties: {name}={value:g} must be <= {MAX_QUANTITY:g}")
        if not 0.0 <= self.m_sur <= 1.0:
            raise SettlementError(f"penalties: m_sur={self.m_sur:g} must lie in [0, 1]: a surplus is sold at most "
                                  "at the DAM price")
        if self.m_def < 1.0:
            raise SettlementError(f"penalties: m_def={self.m_def:g} must be >= 1: a deficit is bought back at least "
                                  "at the DAM price")
        if self.m_sr < 0.0:
            raise SettlementError(f"penalties: m_sr={self.m_sr:g} must be >= 0")
        if self.c_heat_eur_per_mwh is not None and self.c_heat_eur_per_mwh < 0.0:
            raise SettlementError(f"penalties: c_heat_eur_per_mwh={self.c_heat_eur_per_mwh:g} must be >= 0")

    def heat_price(self, case: Case) -> float:
        """``c_heat`` [EUR/MWh_th]."""
        if self.c_heat_eur_per_mwh is not None:
            return float(self.c_heat_eur_per_mwh)
        return HEAT_PRICE_FACTOR * max(case.markets.hpa_tariff_eur_per_mwh)

    def imbalance_prices(self, price_da: np.ndarray, short: np.ndarray | None = None,
                         long: np.ndarray | None = None, labels: Sequence[str] | None = None
                         ) -> tuple[np.ndarray, np.ndarray]:
        """``(π_def, π_sur)`` per period [EUR/MWh] (MODEL_SPEC §10).

        From the DAM price and the multipliers, or the given real series ``short`` (π_def)
        and ``long`` (π_sur), refused where ``short < long`` (naming the period by ``labels``).
        """
        price = np.asarray(price_da, dtype=float)
        if short is None and long is None:
            return (price + (self.m_def - 1.0) * np.abs(price), price - (1.0 - self.m_sur) * np.abs(price))
        if short is None or long is None:
            raise SettlementError("imbalance prices: both the short and the long series are needed")
        short, long = np.asarray(short, dtype=float), np.asarray(long, dtype=float)
        for name, series in (("short", short), ("long", long)):
            if series.shape != price.shape or not np.isfinite(series).all():
                raise SettlementError(f"imbalance prices: the {name} series must hold one finite price per period")
        crossed = np.flatnonzero(short < long)
        if len(crossed):
            t = int(crossed[0])
            where = labels[t] if labels is not None else f"period {t + 1}"
            raise SettlementError(f"imbalance prices at {where}: short {short[t]:g} EUR/MWh is below long "
                                  f"{long[t]:g} EUR/MWh; a deficit must cost at least what a surplus earns")
        return short, long

    def describe(self, case: Case) -> dict[str, float]:
        """The settings in force for ``case`` (``c_heat`` resolved) [-], [EUR/MWh_th]."""
        return {"m_def": self.m_def, "m_sur": self.m_sur, "m_sr": self.m_sr,
                "c_heat_eur_per_mwh": self.heat_price(case)}
