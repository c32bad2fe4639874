"""`PlannerSpec`: what a run records about its planner, stored as JSON, and its check where it is read back.

A light module (no NumPy): the pairs-file reader and the robustness benchmark use it without loading a planner.
"""

from __future__ import annotations

from typing import Any, NotRequired, TypedDict


class PlannerSpec(TypedDict):
    """What a run records about its planner (`Planner.spec()`), stored as JSON: in a run's config
    (`vinadv.identify.PLANNER_SPEC`), a pairs file's params (`"planner"`) and a robustness benchmark.

    Keys:
        name: the registry name or the user's spec (`vin`, `gppn+d4`, `file.py:factory`).
        size: N, the map side the planner was made for.
        config: its hyper-parameters (JSON values; `Planner.config`).
        weights_sha256: SHA-256 (hex) of its weights (`Planner.checksum`); None for a planner without weights.
        device: the device type its forward ran on (`cpu`, `cuda`) where one was chosen (`--device`); absent for the
            planner's default (the VIN's exact CPU engine, a torch planner on the CPU).
    """

    name: str
    size: int
    config: dict[str, Any]
    weights_sha256: str | None
    device: NotRequired[str]


def is_planner_spec(value: object) -> bool:
    """Whether `value` (read back from JSON) has the keys and value types of a `PlannerSpec`."""
    return (
        isinstance(value, dict)
        and isinstance(value.get("name"), str)
        and isinstance(value.get("size"), int)
        and not isinstance(value.get("size"), bool)
        and isinstance(value.get("config"), dict)
        and "weights_sha256" in value
        and (value["weights_sha256"] is None or isinstance(value["weights_sha256"], str))
    )
