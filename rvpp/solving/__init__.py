"""Solve: a delivery day made concrete, the robust counterpart, HiGHS, the plan as plain tables,
diagnosis of infeasible days, and many solves in parallel."""
