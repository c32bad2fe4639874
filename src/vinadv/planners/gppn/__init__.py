"""The GPPN family: the Gated Path Planning Network (`model`: the network, its weights file) and its training entry
(`training`). `vinadv.planners.gppn` keeps the names it had as one module."""

from vinadv.planners.gppn.model import (
    GPPN,
    GPPN_FORMAT,
    MAX_KERNEL,
    MAX_WIDTH,
    GPPNConfig,
    default_gppn_path,
    input_maps,
    load_gppn,
    save_gppn,
    widen_gppn,
)

__all__ = [
    "GPPN",
    "GPPN_FORMAT",
    "MAX_KERNEL",
    "MAX_WIDTH",
    "GPPNConfig",
    "default_gppn_path",
    "input_maps",
    "load_gppn",
    "save_gppn",
    "widen_gppn",
]
