"""The planners vinadv knows by name, and bring-your-own planners by spec.

Each registered planner is declared once (`vinadv.planners.registry.declarations`): its name, spelled with hyphens,
its loader as `"module:function"`, its parameters and its shipped weights, the model zoo (file, sha256, map size,
movement model, licence; `vinadv.planners.registry.models`). Their old spellings are aliases
(`canonical_name`): `vin_robust` is `vin-robust`, the zoo's `vin28_robust` is `vin28-robust`, `vin_mpd32` is
`vin-mpd32`, `gppn_mpd32` is `gppn-mpd32`, `neural_astar_mazes32` is `neural-astar-mazes32`, `neural_astar_mpd5` is
`neural-astar-mpd5`. A family planner given the shipped weights of one of its fixed planners is that planner
(`--planner vin --weights vin28-robust` is `--planner vin-robust`; `resolve_choice`).

`load_planner(spec, size, ...)` gives a `Planner` for:
- `vin` (default): the VIN and its exact engine; weights from `weights=` or the shipped `vin{N}.pt`.
- `vin-robust`: the same VIN architecture with the shipped weights `vin{N}_robust.pt`, trained from the shift start
  (`vinadv.planners.vin.init_shift_kernels`) with adversarial rounds (`vinadv.hardening`).
- `gppn`: the Gated Path Planning Network; weights from `weights=` or the shipped `gppn{N}.pt`.
- `vin-mpd32`, `gppn-mpd32`: the VIN and the GPPN trained by `vin train` / `gppn train` on the MP dataset's 32x32
  `moore` maps (six families' train and valid splits, `maps import --format mpd` then `maps concat`), shipped as
  `vin_mpd32.pt` and `gppn_mpd32.pt`: they plan `moore` maps of 32x32 and refuse others (size, movement model).
- `optimal`: exact shortest paths (the control: what a perfect planner does).
- `astar`: vanilla A* on the maps' movement model, with its expansions (`vinadv.planners.classical.astar`; on
  `moore` maps the Neural A* authors' vanilla A*).
- `wastar`: weighted A*, `f = g + w * h` (`wastar:w=3`; w >= 1, default 2): fewer expansions, suboptimal paths.
- `neural-astar`: Neural A* (Yonetani et al. 2021), the authors' CNN encoder and search on `moore` maps; weights from
  `weights=` or the shipped `neural_astar_mazes32.pt` (converted from the authors' mazes checkpoint; the encoder is
  fully convolutional, so the same file serves every map size).
- `neural-astar-mpd5`: Neural A* with the shipped `neural_astar_mpd5.pt`, trained by `vinadv neural-astar train` on
  the train splits of the five MP families other than mazes (its record beside it).
- `path/to/file.py:factory` or `package.module:factory`: `factory(size: int)` returns a `torch.nn.Module` whose
  `forward(obstacles, goals)` takes obstacles as 0/1 float32 `(B, N, N)` and goals as int64 `(B, 2)` and returns
  `(B, 8, N, N)` logits in DESIGN.md's action order; or an object with `plan_paths` (a search planner,
  `vinadv.planners.search.UserSearchPlanner`: its paths are checked by `check_paths`). Its source file and weights are
  checksummed for run records.
- a registered name followed by `:` and `key=value` pairs separated by commas, `wastar:w=3`: that planner with those
  parameters (`PlannerParam`; a `module:factory` never holds `=`, so the two read apart). Unknown keys and bad values
  are refused with one line naming them; the values are in the planner's config, so run records keep them.
- any of these but `optimal` with `+d4` after it (`gppn+d4`, `file.py:factory+d4`): that planner averaged over the
  8 rotations and flips of the map (`vinadv.planners.symmetric`), an exactly equivariant planner at 8 forwards.

Importing this package is light (no NumPy, no PyTorch): the loading functions are imported when first used.
"""

from __future__ import annotations

from vinadv import lazy_names
from vinadv.planners.registry.base import (
    ALIASES,
    DEFAULT_PLANNER,
    REGISTRY,
    SUFFIX,
    Loader,
    PlannerInfo,
    PlannerParam,
    canonical_name,
    recorded_name,
    register,
    spec_label,
    unregister,
)

# the declarations, run (not `from vinadv.planners.registry import ...`: that would name the whole package)
from vinadv.planners.registry.declarations import LOADERS as _DECLARED  # noqa: F401
from vinadv.planners.registry.models import MODELS, Model, ZooModel, read_zoo, zoo_model

#: names of `vinadv.planners.registry.loading`, imported when first asked for (it brings NumPy)
_LOADING = (
    "PlannerRef",
    "default_weights",
    "list_planners",
    "load_custom",
    "load_planner",
    "load_planner_for",
    "load_symmetric",
    "resolve_choice",
    "same_choice",
    "split_spec",
    "weights_model",
)

__all__ = [
    "spec_label",
    "ALIASES",
    "DEFAULT_PLANNER",
    "MODELS",
    "REGISTRY",
    "SUFFIX",
    "Loader",
    "Model",
    "PlannerInfo",
    "PlannerParam",
    "ZooModel",
    "canonical_name",
    "read_zoo",
    "recorded_name",
    "register",
    "unregister",
    "zoo_model",
    *_LOADING,
]

# NumPy behind them: imported when a planner is loaded
_, __getattr__, __dir__ = lazy_names(__name__, {"loading": _LOADING})
