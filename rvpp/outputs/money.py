"""The unit a figure or a sentence writes money in.

Records, exports and the command line keep money in EUR (columns ``*_eur``); the dashboard
shows it in kEUR. A figure or a sentence that both draw takes a :class:`MoneyUnit`, so the
amounts it is given stay in EUR and only what it writes changes.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class MoneyUnit:
    """``symbol``: the unit's name as written; ``eur``: how many EUR one unit is; ``decimals``: the
    digits written after the point."""

    symbol: str
    eur: float
    decimals: int

    def of(self, amount_eur):
        """``amount_eur`` [EUR] in this unit (a number, an array or a pandas column alike)."""
        return amount_eur / self.eur

    @property
    def hover(self) -> str:
        """The d3 number format of this unit, with thousands separators: for Plotly's hover."""
        return f",.{self.decimals}f"

    def words(self, amount_eur: float) -> str:
        """``58,469 EUR`` or ``58.5 kEUR``: ``amount_eur`` written in this unit."""
        return f"{amount(self.of(amount_eur), self.decimals)} {self.symbol}"


def amount(value: float, decimals: int) -> str:
    """``value`` with thousands separators and ``decimals`` digits after the point, and no sign on an
    amount that rounds to 0 (a profit of exactly 0 is a cost of -0.0 in floating point; "-0.0" reads
    as a loss)."""
    return f"{round(value, decimals) + 0.0:,.{decimals}f}"


# A money axis written as the tables write money: with thousands separators, not 2M or 500k.
MONEY_TICKS = {"exponentformat": "none", "separatethousands": True}

IN_EUR = MoneyUnit("EUR", 1.0, 0)
IN_KEUR = MoneyUnit("kEUR", 1000.0, 1)
