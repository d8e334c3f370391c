"""Settle: the recourse model that settles a plan against realized values, and the audit of plans."""
