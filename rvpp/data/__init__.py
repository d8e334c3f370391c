"""Data in: the case model and its history, market periods, the synthetic default dataset."""
