"""The power-block conversion curve as data (paper STU5; MODEL_SPEC §8).

Electrical output [MW] is the linear interpolation of the breakpoints
``(P_n, η_n·P_n)`` over the thermal input [MW_th]. The MILP encodings live in
:mod:`rvpp.model.piecewise`; the audit and the figures use these functions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..data.case import PowerBlock


@dataclass(frozen=True)
class OnCurve:
    """The on-region of the conversion curve: knots [MW_th] and outputs there [MW]."""

    knots: np.ndarray
    outputs: np.ndarray

    @property
    def lengths(self) -> np.ndarray:
        return np.diff(self.knots)

    @property
    def slopes(self) -> np.ndarray:
        return np.diff(self.outputs) / np.diff(self.knots)

    def __call__(self, x: float | np.ndarray) -> float | np.ndarray:
        """Electrical output for thermal input ``x`` inside the on-region [MW]."""
        return np.interp(x, self.knots, self.outputs)


def curve_output(pb: PowerBlock, x: float | np.ndarray) -> float | np.ndarray:
    """Output of the full breakpoint curve at input ``x`` [MW] (0 below the first point)."""
    inputs = np.array([p for p, _ in pb.breakpoints])
    outputs = np.array([p * eta for p, eta in pb.breakpoints])
    return np.interp(x, inputs, outputs)


def on_curve(pb: PowerBlock) -> OnCurve:
    """Knots of the curve between ``p_in_min`` and ``p_in_max``."""
    inner = [p for p, _ in pb.breakpoints if pb.p_in_min_mw_th < p < pb.p_in_max_mw_th]
    knots = np.array([pb.p_in_min_mw_th, *inner, pb.p_in_max_mw_th])
    return OnCurve(knots=knots, outputs=np.asarray(curve_output(pb, knots)))
