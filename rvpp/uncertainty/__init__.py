"""Uncertainty: forecast bands of every uncertain series, from the history of a case."""
