"""Reserve activation scenarios (MODEL_SPEC §1, the set ``S``) and the reserve each deploys."""

from __future__ import annotations

from enum import StrEnum


class Scenario(StrEnum):
    """Reserve activation scenario (MODEL_SPEC §1, the set ``S``): none, all up reserve called,
    all down reserve called. Every balance that involves reserves holds in each."""

    NONE = "none"
    UP = "up"
    DN = "dn"


SCENARIOS: tuple[Scenario, ...] = tuple(Scenario)


def activation(s: str, up, dn):
    """Reserve deployed in activation scenario ``s``: ``+up``, ``-dn`` or 0 (paper's vectors)."""
    if s == Scenario.UP:
        return up
    if s == Scenario.DN:
        return -dn
    return 0.0
