"""Data and weights of other VIN/GPPN code: the kentsommer PyTorch port, avivt's original `.mat` files, GPPN.

Grid-level conversions only: this package imports `vinadv.grid` and `vinadv.planners`; nothing but the commands
imports it. Conventions of each layout are in `vinadv.interop.formats` and in docs/guide/interop.md.
"""

from vinadv.interop.checkpoints import export_state_dict, gppn_vin_gaps, read_checkpoint
from vinadv.interop.formats import FORMATS, export_maps, import_maps, read_maps

__all__ = [
    "FORMATS",
    "export_maps",
    "export_state_dict",
    "gppn_vin_gaps",
    "import_maps",
    "read_checkpoint",
    "read_maps",
]
