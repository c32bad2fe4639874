"""The second planner shape: a search planner answers paths, not a policy.

A search planner (A*, weighted A*, Neural A*, a user's own) implements

    plan_paths(obstacles (B, N, N) bool, starts (B, 2) int64, goals (B, 2) int64, corner_cutting) -> SearchResult

one path per row, with the cells it expanded where it reports them (and declares so: `Capabilities.expansions`).
`plan_paths` is the hook of the one planning call, `Planner.plan`: its chunk step plans S starts per map as S rows
per map and checks the answer, so a search planner works wherever a `Planner` does (plan, attack, run, identify,
robustness, eval). It declares no policy (`Capabilities.policy` False): `policy_logits` refuses with a
`PlannerError`, and the code that needs logits (the rollout metrics' per-cell policy, `evaluation.protocols`) asks
the capability and says what the planner lacks.

Every search planner's answer passes `check_paths` (as every policy planner's logits pass `check_logits`): one path per
row, every cell in the grid (checked in the planner's own dtype, before vinadv's int16: a float that is not a whole
number or a value outside int16 is refused, never truncated or wrapped into the grid), the first cell the row's start,
each next cell one legal move of the maps' movement model away (so never an obstacle), a termination that says `goal`
exactly where the path ends at the goal, and expansions of the maps' shape, a mask (bool, or numbers that are all 0 or
1: a NaN is refused, never counted). Anything else is a `PlannerError` naming the planner, in one line.

A user's own search planner (`--planner FILE.py:FACTORY` whose factory returns an object with `plan_paths`) is
wrapped by `UserSearchPlanner`: its exceptions (or `sys.exit`) become one-line `PlannerError`s naming it, and its
capabilities are what the object offers.

Attack signals (`attacks.strategies`): `value_maps` is the planner's own cost or heuristic map where it has one
(`Capabilities.value_maps`), else minus the exact cost-to-go (as `optimal`'s); `logits_module` is None, and a
planner whose search is differentiable (`Capabilities.gradients`) offers `differentiable_paths` instead.
"""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.actions import ACTION_DELTAS, N_ACTIONS
from vinadv.grid.moves import DEFAULT_MOVES, check_moves, move_model
from vinadv.grid.paths import PackedPaths
from vinadv.grid.shortest_paths import negative_cost_to_go
from vinadv.planners.interface import Capabilities, Planner, PlannerError
from vinadv.planners.result import GOAL, STEP_LIMIT, TERMINATIONS, PlanResult

if TYPE_CHECKING:
    from collections.abc import Callable

    from torch import nn


@dataclass(kw_only=True, eq=False)
class SearchResult(PlanResult):
    """B searched paths (`PlanResult`: paths, termination) and the cells each search expanded.

    Attributes:
        expanded: `(B, N, N)` bool, the cells search b expanded (closed), start included; None for a planner that
            does not report them (its Exp metric is then undefined).
    """

    expanded: np.ndarray | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.expanded is not None:
            self.expanded = _expansion_mask(self.expanded)
            if self.expanded.ndim != 3 or len(self.expanded) != len(self.paths):
                raise InputError(
                    f"SearchResult: expanded has shape {self.expanded.shape}, expected ({len(self.paths)}, N, N)"
                )

    @classmethod
    def from_paths(cls, paths, goals: np.ndarray, expanded: np.ndarray | None = None) -> SearchResult:
        """A result from B paths (a list of `(L_i, 2)` cell arrays, or `PackedPaths`) and the rows' goals `(B, 2)`:
        termination `goal` where a path ends at its goal, else `step_limit` (the search stopped short of it: no
        path found, or a search budget spent)."""
        packed = paths if isinstance(paths, PackedPaths) else PackedPaths.pack(paths)
        goals = np.asarray(goals, dtype=np.int64).reshape(-1, 2)
        if len(goals) != len(packed):
            raise InputError(f"SearchResult: {len(packed)} paths for {len(goals)} goals")
        return cls(paths=packed, termination=_terminations(packed, goals), expanded=expanded)

    @property
    def expansions(self) -> np.ndarray | None:
        """`(B,)` int64, how many cells each search expanded; None where the planner does not report them."""
        return None if self.expanded is None else self.expanded.sum(axis=(1, 2), dtype=np.int64)

    @property
    def expanded_cells(self) -> PackedPaths | None:
        """The expanded cells of each search packed as paths are (`PackedPaths`, row-major order within a search:
        what a pair stores, `PathPairs.expanded_o`); None where the planner does not report them."""
        return None if self.expanded is None else expanded_cells(self.expanded)


def expanded_cells(expanded: np.ndarray) -> PackedPaths:
    """`(B, N, N)` bool expansion masks as `PackedPaths`: search b's expanded cells in row-major order."""
    owners, rows, cols = np.nonzero(expanded)
    offsets = np.zeros(len(expanded) + 1, dtype=np.int64)
    np.cumsum(np.bincount(owners, minlength=len(expanded)), out=offsets[1:])
    return PackedPaths(np.stack([rows, cols], axis=1), offsets)


def _expansion_mask(expanded) -> np.ndarray:
    """`expanded` as a bool mask, checked in its own dtype first: numbers must be 0 or 1 (a NaN, a negative, a count
    above 1 or a fraction is refused, InputError naming it, never counted as an expanded cell)."""
    arr = np.asarray(expanded)
    if arr.dtype == bool:
        return arr
    if arr.dtype.kind not in "iuf":
        raise InputError(f"SearchResult: expanded has dtype {arr.dtype}, expected a bool mask of the expanded cells")
    bad = (arr != 0) & (arr != 1)  # NaN compares unequal to both
    if bad.any():
        raise InputError(
            f"SearchResult: expanded holds {arr[bad].reshape(-1)[0].item()!r} ({int(bad.sum())} cells); "
            "expected a mask of the expanded cells (True/False or 0/1)"
        )
    return arr.astype(bool)


def _last_cells(paths: PackedPaths) -> np.ndarray:
    """`(B, 2)` int64, the last cell of each non-empty path (`(-1, -1)` for an empty one)."""
    last = np.full((len(paths), 2), -1, np.int64)
    nonempty = paths.lengths > 0
    last[nonempty] = paths.cells[paths.offsets[1:][nonempty] - 1]
    return last


def _terminations(paths: PackedPaths, goals: np.ndarray) -> np.ndarray:
    last = _last_cells(paths)
    return np.where((last[:, 0] == goals[:, 0]) & (last[:, 1] == goals[:, 1]), GOAL, STEP_LIMIT).astype(np.int8)


#: (d_row + 1) * 3 + (d_col + 1) -> action index of that displacement; -1: not a move (staying put)
_ACTION_OF_DELTA = np.full(9, -1, np.int64)
_ACTION_OF_DELTA[(ACTION_DELTAS[:, 0] + 1) * 3 + ACTION_DELTAS[:, 1] + 1] = np.arange(N_ACTIONS)


def check_paths(
    name: str,
    result,
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    corner_cutting: bool = True,
    moves: str = DEFAULT_MOVES,
) -> SearchResult:
    """A search planner's answer for `B` rows, checked: a `SearchResult` (or `PlanResult`, or a sequence of B
    `(L, 2)` paths, given terminations by `SearchResult.from_paths`) whose paths start at the rows' starts and move
    one legal move of `moves` (with `corner_cutting`) at a time on `obstacles (B, N, N)`, whose terminations say
    `goal` exactly where a path ends at its goal, and whose expansions (if any) are `(B, N, N)`. Anything else:
    `PlannerError` naming `name`, one line. Vectorised over all cells of all paths."""
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    starts, goals = np.asarray(starts, dtype=np.int64), np.asarray(goals, dtype=np.int64)
    b, n = obstacles.shape[0], obstacles.shape[1]
    what = f"planner {name!r} returned"
    if isinstance(result, PlanResult):
        expanded = getattr(result, "expanded", None)
        paths, termination = result.paths, result.termination
    elif isinstance(result, PackedPaths) or (isinstance(result, (list, tuple)) and not isinstance(result, str)):
        try:
            paths = result if isinstance(result, PackedPaths) else PackedPaths.pack(result)
        except (InputError, ValueError, TypeError) as exc:
            raise PlannerError(f"{what} paths that are not (L, 2) integer cells: {exc}") from None
        termination, expanded = None, None
    else:
        raise PlannerError(f"{what} {type(result).__name__}; expected a SearchResult or a list of B (L, 2) paths")
    if len(paths) != b:
        raise PlannerError(f"{what} {len(paths)} paths for {b} rows")
    if b == 0:
        return SearchResult(paths=paths, termination=np.zeros(0, np.int8), expanded=expanded)

    def refuse(bad: np.ndarray, rows: np.ndarray, text: str) -> None:
        """Refuse when any of `bad` (per cell or per row, with the row of each in `rows`) is set."""
        if bad.any():
            first = int(np.flatnonzero(bad)[0])
            count = len(np.unique(rows[bad]))
            raise PlannerError(f"{what} {text(first)} (on {count} of {b} rows)")

    lengths, rows_of_path = paths.lengths, np.arange(b)
    refuse(lengths == 0, rows_of_path, lambda i: f"an empty path for row {i}: a path holds at least its start")
    cells = paths.cells.astype(np.int64)
    owner = paths.owners()
    # (not `.any(axis=1)`: NumPy's reductions over a length-2 axis are many times slower than the two columns)
    r, c = cells[:, 0], cells[:, 1]
    outside = (r < 0) | (r >= n) | (c < 0) | (c >= n)
    refuse(outside, owner, lambda i: f"cell {tuple(cells[i].tolist())} outside the {n}x{n} grid (row {owner[i]})")
    first = cells[paths.offsets[:-1]]
    wrong_start = (first[:, 0] != starts[:, 0]) | (first[:, 1] != starts[:, 1])
    refuse(
        wrong_start,
        rows_of_path,
        lambda i: (
            f"a path for row {i} that starts at {tuple(first[i].tolist())}, not at its start "
            f"{tuple(starts[i].tolist())}"
        ),
    )
    # moves: cell k to cell k + 1 of the same path, one of the model's actions, legal on the map
    model = move_model(moves)
    same = owner[1:] == owner[:-1]
    src, dst, row = cells[:-1][same], cells[1:][same], owner[1:][same]
    delta = dst - src
    near = (np.abs(delta[:, 0]) <= 1) & (np.abs(delta[:, 1]) <= 1)
    clipped = np.clip(delta, -1, 1) + 1
    action = np.where(near, _ACTION_OF_DELTA[clipped[:, 0] * 3 + clipped[:, 1]], -1)
    # legal: one of the model's moves, into a free cell; without corner cutting a diagonal move also needs both cells
    # beside it free (the rule of `grid.shortest_paths.valid_moves`, at the path's moves only)
    flat = obstacles.reshape(-1)  # flat indices: faster than indexing three axes

    def blocked(rows, rr, cc):
        return flat[(rows * n + rr) * n + cc]

    legal = (action >= 0) & (action < model.n_actions) & ~blocked(row, dst[:, 0], dst[:, 1])
    if not corner_cutting:
        k = np.flatnonzero(legal & (delta[:, 0] != 0) & (delta[:, 1] != 0))
        legal[k] = ~blocked(row[k], dst[k, 0], src[k, 1]) & ~blocked(row[k], src[k, 0], dst[k, 1])
    rule = f"{model.name}{'' if corner_cutting else ', no corner cutting'}"
    refuse(
        ~legal,
        row,
        lambda i: (
            f"a path for row {row[i]} that moves from {tuple(src[i].tolist())} to {tuple(dst[i].tolist())}, "
            f"not one legal move ({rule}: into a free cell, one step away)"
        ),
    )
    derived = _terminations(paths, goals)
    if termination is None:
        termination = derived
    else:
        termination = np.asarray(termination)
        if termination.shape != (b,) or termination.dtype.kind not in "iu":
            raise PlannerError(f"{what} terminations of shape {termination.shape}; expected ({b},) codes")
        refuse(
            (termination < 0) | (termination >= len(TERMINATIONS)),
            rows_of_path,
            lambda i: f"termination code {int(termination[i])} for row {i}; expected 0..{len(TERMINATIONS) - 1}",
        )
        refuse(
            (termination == GOAL) != (derived == GOAL),
            rows_of_path,
            lambda i: (
                f"termination {TERMINATIONS[int(termination[i])]!r} for row {i}, whose path ends at "
                f"{tuple(_last_cells(paths)[i].tolist())} with the goal at {tuple(goals[i].tolist())}"
            ),
        )
    if expanded is not None:
        expanded = np.asarray(expanded)
        if expanded.shape != (b, n, n) or expanded.dtype != bool:
            raise PlannerError(
                f"{what} expansions of shape {expanded.shape} and dtype {expanded.dtype}; expected ({b}, {n}, {n}) bool"
            )
    return SearchResult(paths=paths, termination=termination, expanded=expanded)


class SearchPlanner(Planner):
    """A planner that searches: `plan_paths` gives the paths (and expansions); no policy logits.

    Subclasses set `name`, `size`, `moves` (the movement model they search, `vinadv.grid.moves`), `capabilities`
    (what they offer beyond paths: expansions, their own value maps, gradients) and implement `plan_paths`. They may
    override `value_maps` (their own cost or heuristic map) and `differentiable_paths`. `plan` chunks the rows and
    checks every answer (`check_paths`, on the planner's movement model).
    """

    capabilities = Capabilities()
    #: None: `plan` gives `plan_paths` all the rows at once unless the caller gives a chunk size (the planner batches
    #: its own work)
    chunk_size = None

    @abstractmethod
    def plan_paths(
        self, obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool = True
    ) -> SearchResult:
        """One searched path per row: obstacles `(B, N, N)` bool, starts and goals `(B, 2)` int64 `(row, col)`; the
        hook of `plan`, which checks its answer."""

    def _result_type(self) -> type[PlanResult]:
        return SearchResult

    def _chunk_planner(self, corner_cutting: bool) -> Callable[[np.ndarray, np.ndarray, np.ndarray], SearchResult]:
        """`plan`'s step: the chunk's S starts per map as S rows per map (row `b * S + s`), searched by `plan_paths`
        and checked by `check_paths`."""

        def step(obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray) -> SearchResult:
            per_map = starts.shape[1]
            if per_map != 1:
                obstacles, goals = np.repeat(obstacles, per_map, axis=0), np.repeat(goals, per_map, axis=0)
            rows = starts.reshape(-1, 2)
            raw = self.plan_paths(obstacles, rows, goals, corner_cutting)
            return check_paths(self.name, raw, obstacles, rows, goals, corner_cutting, self.moves)

        return step

    def policy_logits(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        raise PlannerError(f"planner {self.name!r} is a search planner: it answers paths, not policy logits")

    @property
    def differentiable_paths(self) -> nn.Module | None:
        """A module `module(obstacles (B,N,N) float, starts (B,2) int64, goals (B,2) int64) -> (B, N, N)` float path
        map, differentiable with respect to the obstacles (the saliency attack uses it), where
        `capabilities.gradients`; None for a planner whose search has no gradients."""
        return None

    def value_maps(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        """Minus the exact cost-to-go under the planner's movement model, `(B, N, N)` float64 (NaN where the goal
        cannot be reached): the ranking signal of a search planner without a cost or heuristic map of its own."""
        obstacles = np.ascontiguousarray(obstacles, dtype=bool)
        self._check_size(obstacles)
        # with corner cutting, whatever the maps' rule: a ranking signal, and the planner is told the rule only when
        # it plans
        return negative_cost_to_go(obstacles, goals, True, self.moves)


class UserSearchPlanner(SearchPlanner):
    """A user's own search planner: any object with `plan_paths(obstacles, starts, goals, corner_cutting)` (the
    `SearchPlanner` contract; a `SearchResult`, or a list of B `(L, 2)` paths), from `--planner FILE.py:FACTORY`.

    Optional attributes of the object: `moves` (the movement model it plans, default `octile`: maps of another
    model are refused, as for every planner), `value_maps(obstacles, goals) -> (B, N, N)` (its own cost or heuristic
    map, for the key-points ranking; default minus the exact cost-to-go), `differentiable_paths` (a torch module,
    for the saliency attack) and `capabilities` (a `Capabilities`, or a dict of some of its fields: say
    `{"expansions": True}` where its answers carry the expanded cells, `"start_values": True` where its `value_maps`
    takes the starts as a third argument). Its capabilities are what it offers: value
    maps where it has `value_maps`, gradients where `differentiable_paths` is not None, expansions where it declares
    them; never a policy. Whatever it raises, `sys.exit` included, is one `PlannerError` naming the planner.
    """

    def __init__(self, impl, name: str, size: int, checksum: str | None = None, config: dict | None = None):
        self.impl, self.name, self.size = impl, name, int(size)
        moves = getattr(impl, "moves", DEFAULT_MOVES)
        try:
            self.moves = check_moves(moves)
        except InputError:
            raise PlannerError(f"planner {name!r}: its moves {moves!r} is not a movement model") from None
        self._checksum = checksum
        self._config = dict(config or {})
        declared = Capabilities.from_mapping(name, getattr(impl, "capabilities", {}))
        if declared.policy:
            raise PlannerError(f"planner {name!r}: an object with plan_paths is a search planner; it has no policy")
        self.capabilities = Capabilities(
            value_maps=declared.value_maps or callable(getattr(impl, "value_maps", None)),
            gradients=declared.gradients or getattr(impl, "differentiable_paths", None) is not None,
            expansions=declared.expansions,
            start_values=declared.start_values and callable(getattr(impl, "value_maps", None)),
        )

    def _call(self, what: str, method, *args):
        try:
            return method(*args)
        except (Exception, SystemExit) as exc:  # a user's code: say which planner failed, in one line
            raise PlannerError(f"planner {self.name!r}: {what} failed: {type(exc).__name__}: {exc}") from None

    def plan_paths(self, obstacles, starts, goals, corner_cutting: bool = True):
        return self._call("plan_paths", self.impl.plan_paths, obstacles, starts, goals, corner_cutting)

    def value_maps(self, obstacles: np.ndarray, goals: np.ndarray, starts: np.ndarray | None = None) -> np.ndarray:
        own = getattr(self.impl, "value_maps", None)
        if own is None:
            return super().value_maps(obstacles, goals)
        obstacles = np.ascontiguousarray(obstacles, dtype=bool)
        args = [obstacles, np.asarray(goals, dtype=np.int64)]
        if starts is not None and self.capabilities.start_values:  # only an object that declares it takes starts
            args.append(np.asarray(starts, dtype=np.int64))
        value = np.asarray(self._call("value_maps", own, *args))
        if value.shape != obstacles.shape or value.dtype.kind != "f":
            raise PlannerError(
                f"planner {self.name!r} returned value maps of shape {value.shape} and dtype {value.dtype}; "
                f"expected {obstacles.shape} float"
            )
        return value

    @property
    def differentiable_paths(self):
        return getattr(self.impl, "differentiable_paths", None)
