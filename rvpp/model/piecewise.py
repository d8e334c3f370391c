"""Exact MILP encodings of the power-block conversion curve (paper STU5, STU_SOS).

The curve maps thermal input [MW_th] to electrical output [MW] by linear
interpolation of the breakpoints ``(P_n, η_n·P_n)``. While the turbine is on, the
input lies in ``[P_min, P_max]`` (STU3-STU4), so only the on-region of the curve is
encoded; off, input and output are zero. Two encodings are offered:

* ``incremental`` (default): ``x = P_min·u + Σk δ_k``, ``e = f(P_min)·u + Σk s_k·δ_k``
  with fill-order binaries ``w_k`` (segment k is full before k+1 starts). Usually the
  tightest linear relaxation.
* ``convex_combination``: ``x = Σn K_n·λ_n``, ``e = Σn f(K_n)·λ_n``, ``Σ λ = u`` with one
  binary per segment and adjacency ``λ_n ≤ z_{n-1} + z_n`` (the SOS2 role of STU_SOS3-6).
"""

from __future__ import annotations

import pyomo.environ as pyo

from .curve import OnCurve


def add_incremental(b, name: str, index: list, x, e, u, curve: OnCurve) -> None:
    """Incremental encoding of ``e[s,t] = f(x[s,t])`` when ``u[t] = 1``; ``x = e = 0`` when off.

    ``index`` lists the ``(s, t)`` pairs. Adds ``{name}_delta[s,t,k]`` [MW_th] and the
    fill binaries ``{name}_fill[s,t,k]`` (1 when segment k is full).
    """
    segments = list(range(len(curve.lengths)))
    inner = segments[:-1]
    lengths, slopes = curve.lengths, curve.slopes
    delta = pyo.Var(index, segments, domain=pyo.NonNegativeReals,
                    bounds=lambda _, s, t, k: (0.0, float(lengths[k])))
    fill = pyo.Var(index, inner, domain=pyo.Binary)
    b.add_component(f"{name}_delta", delta)
    b.add_component(f"{name}_fill", fill)
    b.add_component(f"{name}_input", pyo.Constraint(index, rule=lambda _, s, t: (
        x[s, t] == float(curve.knots[0]) * u[t] + sum(delta[s, t, k] for k in segments))))
    b.add_component(f"{name}_output", pyo.Constraint(index, rule=lambda _, s, t: (
        e[s, t] == float(curve.outputs[0]) * u[t] + sum(float(slopes[k]) * delta[s, t, k] for k in segments))))
    b.add_component(f"{name}_open", pyo.Constraint(index, segments, rule=lambda _, s, t, k: (
        delta[s, t, k] <= float(lengths[k]) * (u[t] if k == 0 else fill[s, t, k - 1]))))
    b.add_component(f"{name}_full", pyo.Constraint(index, inner, rule=lambda _, s, t, k: (
        delta[s, t, k] >= float(lengths[k]) * fill[s, t, k])))


def add_convex_combination(b, name: str, index: list, x, e, u, curve: OnCurve) -> None:
    """Convex-combination encoding with one binary per segment (SOS2 by adjacency).

    Adds weights ``{name}_lambda[s,t,n]`` and segment binaries ``{name}_segment[s,t,k]``.
    """
    knots = list(range(len(curve.knots)))
    segments = list(range(len(curve.lengths)))
    lam = pyo.Var(index, knots, domain=pyo.NonNegativeReals, bounds=(0.0, 1.0))
    seg = pyo.Var(index, segments, domain=pyo.Binary)
    b.add_component(f"{name}_lambda", lam)
    b.add_component(f"{name}_segment", seg)
    b.add_component(f"{name}_input", pyo.Constraint(index, rule=lambda _, s, t: (
        x[s, t] == sum(float(curve.knots[n]) * lam[s, t, n] for n in knots))))
    b.add_component(f"{name}_output", pyo.Constraint(index, rule=lambda _, s, t: (
        e[s, t] == sum(float(curve.outputs[n]) * lam[s, t, n] for n in knots))))
    b.add_component(f"{name}_weights", pyo.Constraint(index, rule=lambda _, s, t: (
        sum(lam[s, t, n] for n in knots) == u[t])))
    b.add_component(f"{name}_one_segment", pyo.Constraint(index, rule=lambda _, s, t: (
        sum(seg[s, t, k] for k in segments) == u[t])))
    b.add_component(f"{name}_adjacent", pyo.Constraint(index, knots, rule=lambda _, s, t, n: (
        lam[s, t, n] <= sum(seg[s, t, k] for k in (n - 1, n) if k in segments))))
