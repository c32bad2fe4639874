"""The fast batched planning engine: one value map per map, shared by its rollouts, all in one compiled kernel.

Paths and termination reasons are those of `vinadv.planners.vin.reference.plan_reference` (the ports' way: re-run the
float32 PyTorch VIN at every step). The engine gets there differently, map by map, in parallel over maps:

1. Value map. It does not depend on the agent's cell, so each map's VIN runs once (`_value_iteration`).
2. Rollouts (DESIGN.md's rule) right after, while the map's q is in cache; the action of a cell (argmax of the
   logits, the lowest index on ties) is computed only when a rollout stands on it, about 15 cells of 784.
3. Near ties. The engine's arithmetic is not torch's, so logits differ by rounding; where the two best logits of a
   cell are closer than a margin that bounds that difference, the cell is uncertain, and a rollout that steps on
   one is re-done (same compiled rollout) with the reference's own decision at every cell of that map:
   `replay.exact_actions`, from PyTorch's value map replayed bit for bit without calling PyTorch (under
   1 ms a map, where a batch-1 `q_values` costs ~3 ms on a quiet core and far more beside a busy one).

The step limit 2L comes from an A* search (`vinadv.grid.optimal_moves`) run only for the few rollouts that get
that far; maps are split between threads by `vinadv.planners.batching.over_maps`. `action_maps` gives the action
of every cell (uncertain: -1), for inspection and benchmarks.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numba
import numpy as np

from vinadv.grid.actions import ACTION_DELTAS, SQRT2
from vinadv.grid.optimal_moves import optimal_moves_kernel
from vinadv.planners.batching import DEFAULT_CHUNK, chunk_slices, over_maps
from vinadv.planners.result import (
    GOAL,
    STEP_LIMIT,
    TERMINATIONS,
    PlanResult,
    check_plan_inputs,
)
from vinadv.planners.rollout import MOVED, rollout_step
from vinadv.planners.vin.arrays import GOAL_VALUE, VINWeights, as_vin_weights
from vinadv.planners.vin.flat import kernel_taps, layout, zero_row_gaps
from vinadv.planners.vin.replay import best_and_gap, exact_actions

if TYPE_CHECKING:
    from vinadv.planners.vin.model import VIN

__all__ = ["DEFAULT_CHUNK", "PlanResult", "TERMINATIONS", "plan_batch", "plan_maps", "action_maps"]

#: a cell is uncertain when its two best logits are closer than REL_MARGIN * (logit scale of its map).
REL_MARGIN = 5e-6
UNDECIDED = -1  # rollout code: stepped on an uncertain cell, to be re-done with torch's logits


def action_maps(model: VINWeights | VIN, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
    """Action of every cell, `(B, N, N)` int8 in 0..7, or -1 (uncertain) where the two best logits are a near tie.

    Runs the compiled value iteration (`_action_maps_kernel`) in parallel over maps.
    """
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    goals = np.ascontiguousarray(goals, dtype=np.int64)
    p = FoldedVIN.from_weights(as_vin_weights(model))
    actions = np.empty(obstacles.shape, dtype=np.int8)
    over_maps(
        len(obstacles),
        lambda lo, hi: _action_maps_kernel(
            obstacles[lo:hi],
            goals[lo:hi],
            p.reward_w,
            p.reward_b,
            p.goal_value,
            p.q_w,
            p.w,
            p.fc,
            p.k,
            REL_MARGIN,
            actions[lo:hi],
        ),
        cost=_map_cost(p, obstacles.shape[1]),
    )
    return actions


class FoldedVIN:
    """A VIN's weights rearranged for the engine (float64 where computed once per map, float32 in the hot loop).

    `h` (2 -> l_h, 3x3, bias) and `r` (l_h -> 1, 1x1) are linear with nothing between them, so they fold into one
    3x3 reward convolution `reward_w (2, 3, 3)` plus `reward_b`. `q_w (l_q, 3, 3)` float64 gives the constant reward
    term of every step, `w (l_q, 3, 3)` float32 the value term (the hot loop), `fc (A, l_q)` float64 the logits.
    """

    def __init__(self, reward_w, reward_b, q_w, w, fc, k, goal_value):
        self.reward_w, self.reward_b, self.q_w, self.w, self.fc, self.k = reward_w, reward_b, q_w, w, fc, k
        self.goal_value = goal_value

    @classmethod
    def from_weights(cls, weights: VINWeights) -> FoldedVIN:
        sd = {name: np.asarray(a, dtype=np.float64) for name, a in weights.state.items()}
        r = sd["r.weight"][0, :, 0, 0]  # (l_h,)
        return cls(
            reward_w=np.ascontiguousarray(np.einsum("h,hcij->cij", r, sd["h.weight"])),
            reward_b=float(r @ sd["h.bias"]),
            q_w=np.ascontiguousarray(sd["q.weight"][:, 0]),
            w=np.ascontiguousarray(sd["w"][:, 0], dtype=np.float32),
            fc=np.ascontiguousarray(sd["fc.weight"]),
            k=int(weights.config.k),
            goal_value=float(GOAL_VALUE),
        )


def _map_cost(p: FoldedVIN, n: int) -> float:
    """The value iteration's multiply-adds on one N x N map (`over_maps` runs the maps in rounds of bounded work, so
    Ctrl-C and SIGTERM are seen between them, whatever k)."""
    return 9.0 * (p.k + 1) * p.q_w.shape[0] * n * n


# The kernels work on the flat layout of `vinadv.planners.vin.flat`. The value iteration also keeps the value map
# shifted by one cell either way (vm[i] = v[i - 1], vp[i] = v[i + 1]): with those, every one of its loads starts on a
# vector boundary (a 32-byte load that straddles two cache lines costs two).


@numba.njit(cache=True, nogil=True)
def _action_maps_kernel(obstacles, goals, reward_w, reward_b, goal_value, q_w, w, fc, k, rel_margin, actions):
    n, lq = obstacles.shape[1], q_w.shape[0]
    reward_q, q, v, vm, vp, best, best2, work = _scratch(n, lq)
    for b in range(obstacles.shape[0]):
        _reward_terms(obstacles[b], goals[b, 0], goals[b, 1], reward_w, reward_b, goal_value, q_w, reward_q, work)
        _value_iteration(reward_q, v, vm, vp, best, best2, w, k, q, n)
        _decide(q, fc, n, rel_margin, actions[b])


@numba.njit(cache=True, nogil=True)
def _scratch(n, lq):
    """Per-thread arrays in the flat layout: reward_q and q `(l_q, S)`; v, vm, vp, best and best2 `(S,)`; work
    `(2, S)` float64 for the reward terms.

    S is the layout's size rounded up to 4 KiB, and what the value iteration's loops store (best, best2, q) sits
    1 KiB below what they load (value maps, reward_q), modulo 4 KiB: a load whose address matches a store still in
    flight in its low 12 bits waits for it (4K aliasing), which made the loop 25-40% slower when these arrays lay
    back to back. Starts on a 64-byte boundary.
    """
    stride = (layout(n)[3] + 1023) // 1024 * 1024
    rows = lq + 3
    buf = np.zeros(2 * rows * stride + 256 + 16, dtype=np.float32)
    start = (-buf.ctypes.data % 64) // 4
    stores = buf[start : start + rows * stride].reshape(rows, stride)
    start += rows * stride + 256
    loads = buf[start : start + rows * stride].reshape(rows, stride)
    work = np.zeros((2, stride))
    return loads[:lq], stores[:lq], loads[lq], loads[lq + 1], loads[lq + 2], stores[lq], stores[lq + 1], work


@numba.njit(cache=True, nogil=True)
def _reward_terms(obs, gr, gc, reward_w, reward_b, goal_value, q_w, reward_q, work):
    """reward_q[c] = q_w[c] * r, r = folded reward (zero outside the grid), in float64, stored float32. Flat
    layout; `work` is float64 scratch `(2, size)`, zero outside the map's cells."""
    n, lq = obs.shape[0], reward_q.shape[0]
    width, p0, length = layout(n)[:3]
    padded, r = work[0], work[1]
    for i in range(n):
        for j in range(n):
            padded[p0 + i * width + j] = obs[i, j]
    _conv3x3(padded, reward_w[0], reward_b, r, width, p0, length)
    zero_row_gaps(r, n)
    for di in range(3):  # the goal image is 0 but at the goal: it reaches only the goal's 3x3 neighbourhood
        for dj in range(3):
            i, j = gr - di + 1, gc - dj + 1
            if 0 <= i < n and 0 <= j < n:
                r[p0 + i * width + j] += goal_value * reward_w[1, di, dj]
    for c in range(lq):
        _conv3x3(r, q_w[c], 0.0, reward_q[c], width, p0, length)


@numba.njit(cache=True, nogil=True)
def _conv3x3(x, w, bias, out, width, p0, length):
    """out[p] = bias + sum of w * the 3x3 neighbourhood of p, for p in p0 .. p0 + length - 1 (flat layout)."""
    u0, u1, u2 = x[p0 - width - 1 :], x[p0 - 1 :], x[p0 + width - 1 :]
    o = out[p0 : p0 + length]
    for t in range(length):
        o[t] = (
            bias
            + w[0, 0] * u0[t]
            + w[0, 1] * u0[t + 1]
            + w[0, 2] * u0[t + 2]
            + w[1, 0] * u1[t]
            + w[1, 1] * u1[t + 1]
            + w[1, 2] * u1[t + 2]
            + w[2, 0] * u2[t]
            + w[2, 1] * u2[t + 1]
            + w[2, 2] * u2[t + 2]
        )


@numba.njit(cache=True, nogil=True)
def _publish(best, v, vm, vp, n):
    """v = best with its row gaps zeroed, and its shifted copies vm[i] = v[i - 1], vp[i] = v[i + 1]."""
    zero_row_gaps(best, n)
    p0, length = layout(n)[1:3]
    src = best[p0 : p0 + length]
    for dst in (v[p0 : p0 + length], vm[p0 + 1 : p0 + 1 + length], vp[p0 - 1 : p0 - 1 + length]):
        for t in range(length):  # one loop per copy: three stores in one loop would not vectorise
            dst[t] = src[t]


@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def _value_iteration(reward_q, v, vm, vp, best, best2, w, k, q, n):
    """The hot loop: v = max over channels of reward_q (the first q layer), then k times q = reward_q + (w * v),
    v = max over channels; the last q goes to `q`. N x N map, flat layout. Overwrites v, vm, vp, best, best2.

    Float32, one channel per pass (its nine weights stay in registers; two channels per pass share the loads of v
    but spill weights, measured slower), each sum in three partial sums (a chain of nine dependent FMAs would wait
    on latency). The max is `a if a > b else b` into the other of two buffers: that compiles to one vmaxps, where
    `np.maximum` adds NaN handling (six instructions) and a max stored back into its own input a masked store.
    """
    lq = reward_q.shape[0]
    width, p0, length = layout(n)[:3]
    src = best2[p0 : p0 + length]
    src[:] = np.float32(-np.inf)
    for c in range(lq):  # v of the first q layer: the max of reward_q over channels
        out = best if c % 2 == 0 else best2
        dst, rq = out[p0 : p0 + length], reward_q[c, p0 : p0 + length]
        for t in range(length):
            a, b = rq[t], src[t]
            dst[t] = a if a > b else b
        src = dst
    _publish(out, v, vm, vp, n)
    x0, x1, x2 = vm[p0 - width :], vm[p0:], vm[p0 + width :]  # left neighbours: rows above, same, below
    y0, y1, y2 = v[p0 - width :], v[p0:], v[p0 + width :]
    z0, z1, z2 = vp[p0 - width :], vp[p0:], vp[p0 + width :]  # right neighbours
    for it in range(k):
        last = it == k - 1
        src = best2[p0 : p0 + length]
        src[:] = np.float32(-np.inf)
        for c in range(lq):
            out = best if c % 2 == 0 else best2
            dst = out[p0 : p0 + length]
            rq = reward_q[c, p0 : p0 + length]
            w00, w01, w02, w10, w11, w12, w20, w21, w22 = kernel_taps(w[c])
            if not last:
                for t in range(length):
                    a = (
                        (rq[t] + w00 * x0[t] + w01 * y0[t] + w02 * z0[t])
                        + (w10 * x1[t] + w11 * y1[t] + w12 * z1[t])
                        + (w20 * x2[t] + w21 * y2[t] + w22 * z2[t])
                    )
                    b = src[t]
                    dst[t] = a if a > b else b
            else:  # the same sums, kept: the final q (a branch inside the loop would stop it vectorising)
                qc = q[c, p0 : p0 + length]
                for t in range(length):
                    qc[t] = (
                        (rq[t] + w00 * x0[t] + w01 * y0[t] + w02 * z0[t])
                        + (w10 * x1[t] + w11 * y1[t] + w12 * z1[t])
                        + (w20 * x2[t] + w21 * y2[t] + w22 * z2[t])
                    )
            src = dst
        if not last:
            _publish(out, v, vm, vp, n)


@numba.njit(cache=True, nogil=True)
def _margin(q, fc, n, rel_margin):
    """Near-tie margin of a map: rel_margin * max |q| over the map * max_a sum_c |fc[a, c]| (a bound on how far
    rounding moves a logit, times the relative error of q)."""
    n_act, lq = fc.shape[0], fc.shape[1]
    width, p0 = layout(n)[:2]
    qmax = 0.0
    for c in range(lq):
        for i in range(n):
            for j in range(n):
                qmax = max(qmax, abs(q[c, p0 + i * width + j]))
    fmax = 0.0
    for a in range(n_act):
        s = 0.0
        for c in range(lq):
            s += abs(fc[a, c])
        fmax = max(fmax, s)
    return rel_margin * qmax * fmax


@numba.njit(cache=True, nogil=True)
def _action_at(q, fc, cell, margin, logits):
    """Action of the cell at flat index `cell`: argmax of the float64 logits (lowest index on ties), UNDECIDED
    where the best two are within `margin`. `logits` is scratch of length A."""
    n_act, lq = fc.shape[0], fc.shape[1]
    for a in range(n_act):
        s = 0.0
        for c in range(lq):
            s += fc[a, c] * q[c, cell]
        logits[a] = s
    top, gap = best_and_gap(logits)
    return top if gap > margin else UNDECIDED


@numba.njit(cache=True, nogil=True)
def _decide(q, fc, n, rel_margin, actions):
    """Action of every cell (`_action_at`) into `actions (N, N)`."""
    margin = _margin(q, fc, n, rel_margin)
    logits = np.empty(fc.shape[0])
    width, p0 = layout(n)[:2]
    for i in range(n):
        for j in range(n):
            actions[i, j] = _action_at(q, fc, p0 + i * width + j, margin, logits)


@numba.njit(cache=True, nogil=True)
def _plan_kernel(
    lo,
    hi,
    obstacles,
    goals,
    starts,
    reward_w,
    reward_b,
    goal_value,
    q_w,
    w,
    fc,
    k,
    rel_margin,
    corner_cutting,
    deltas,
    cells,
    lengths,
    terms,
):
    """Maps lo..hi-1: value map, then the rollouts of the map's S starts (rollout b * S + s), deciding the action
    of a cell only when a rollout stands on it. cells: `(B * S, N * N, 2)`; writes lengths and terms `(B * S,)`."""
    n, lq, n_starts = obstacles.shape[1], q_w.shape[0], starts.shape[1]
    reward_q, q, v, vm, vp, best, best2, work = _scratch(n, lq)
    logits = np.empty(fc.shape[0])
    stamp = np.zeros((n, n), dtype=np.int64)  # t + 1 on the cells rollout t has visited
    no_actions = np.empty((0, 0), dtype=np.int8)
    for b in range(lo, hi):
        _reward_terms(obstacles[b], goals[b, 0], goals[b, 1], reward_w, reward_b, goal_value, q_w, reward_q, work)
        _value_iteration(reward_q, v, vm, vp, best, best2, w, k, q, n)
        margin = _margin(q, fc, n, rel_margin)
        for s in range(n_starts):
            _rollout(
                obstacles,
                goals,
                starts,
                b,
                s,
                q,
                fc,
                margin,
                logits,
                no_actions,
                corner_cutting,
                deltas,
                stamp,
                cells,
                lengths,
                terms,
            )


@numba.njit(cache=True, nogil=True)
def _redo_kernel(rollouts, map_of, actions, obstacles, goals, starts, corner_cutting, deltas, cells, lengths, terms):
    """Rollouts `rollouts (R,)` (index b * S + s) again, the action of every cell given: `actions[map_of[i]]`
    `(N, N)` for rollout i (`exact_actions` of its map)."""
    n, n_starts = obstacles.shape[1], starts.shape[1]
    stamp = np.zeros((n, n), dtype=np.int64)
    q, fc, logits = np.empty((0, 0), dtype=np.float32), np.empty((0, 0)), np.empty(0)  # unused: actions are given
    for i in range(len(rollouts)):
        b, s = rollouts[i] // n_starts, rollouts[i] % n_starts
        _rollout(
            obstacles,
            goals,
            starts,
            b,
            s,
            q,
            fc,
            0.0,
            logits,
            actions[map_of[i]],
            corner_cutting,
            deltas,
            stamp,
            cells,
            lengths,
            terms,
        )


@numba.njit(cache=True, nogil=True)
def _rollout(
    obstacles, goals, starts, b, s, q, fc, margin, logits, actions, corner_cutting, deltas, stamp, cells, lengths, terms
):
    """Rollout t = b * S + s (DESIGN.md's rule, as `reference.rollout`) into cells[t], lengths[t], terms[t]. The
    action of a cell: `actions[r, c]` when `actions` is not empty, else `_action_at` on the map's q (UNDECIDED on
    a near tie ends the rollout, to be re-done).

    The step limit 2L needs L, the optimal move count (an A* search); a rollout needs it only once it has made
    2 * max(|dr|, |dc|) moves (a lower bound of 2L), which few do, so L is searched for then."""
    n, n_starts = obstacles.shape[1], starts.shape[1]
    width, p0 = layout(n)[:2]
    t = b * n_starts + s
    r, c = starts[b, s, 0], starts[b, s, 1]
    gr, gc = goals[b, 0], goals[b, 1]
    cells[t, 0, 0] = r
    cells[t, 0, 1] = c
    length = 1
    stamp[r, c] = t + 1
    limit, exact = 2 * max(abs(r - gr), abs(c - gc)), False
    while True:
        if r == gr and c == gc:
            term = GOAL
            break
        if length - 1 >= limit and not exact:
            moves = np.empty(1, dtype=np.int64)
            optimal_moves_kernel(  # the engine plans octile moves (`vinadv.grid.moves`): diagonal sqrt 2
                obstacles, goals, starts[b, s : s + 1], np.full(1, b), corner_cutting, deltas, SQRT2, moves
            )
            limit, exact = 2 * (moves[0] if moves[0] >= 0 else n * n), True
        if length - 1 >= limit:
            term = STEP_LIMIT
            break
        if actions.shape[0]:
            a = actions[r, c]
        else:
            a = _action_at(q, fc, p0 + r * width + c, margin, logits)
            if a < 0:
                term = UNDECIDED
                break
        term, r, c, length = rollout_step(obstacles, b, t, r, c, a, corner_cutting, deltas, stamp, cells, length)
        if term != MOVED:
            break
    lengths[t] = length
    terms[t] = term


def plan_batch(
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    model: VINWeights | VIN,
    corner_cutting: bool = True,
    chunk_size: int = DEFAULT_CHUNK,
    progress: bool = False,
) -> PlanResult:
    """Plan one path per map with `model`, for any batch size, `chunk_size` maps at a time.

    Args:
        obstacles: `(B, N, N)` bool, True = obstacle.
        starts, goals: `(B, 2)` int `(row, col)`.
        model: `VINWeights` or a PyTorch `VIN`. corner_cutting: whether a diagonal move may pass between two obstacles.
        chunk_size: maps per chunk (bounds memory). progress: show a tqdm bar over chunks.

    Returns:
        `PlanResult`, identical to `plan_reference` on the same inputs (see the module docstring).
    """
    obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
    return plan_maps(obstacles, goals, starts[:, None, :], model, corner_cutting, chunk_size, progress)


def plan_maps(
    obstacles: np.ndarray,
    goals: np.ndarray,
    starts: np.ndarray,
    model: VINWeights | VIN,
    corner_cutting: bool = True,
    chunk_size: int = DEFAULT_CHUNK,
    progress: bool = False,
    stats: dict | None = None,
) -> PlanResult:
    """Plan from S starts per map: `starts (B, S, 2)`; path `i * S + s` is from start `s` of map `i`.

    The value map of each map is computed once and shared by its S rollouts.
    """
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    goals = np.ascontiguousarray(goals, dtype=np.int64)
    starts = np.ascontiguousarray(starts, dtype=np.int64)
    if starts.ndim != 3 or starts.shape[0] != len(obstacles) or starts.shape[2] != 2:
        raise ValueError(f"starts has shape {starts.shape}, expected ({len(obstacles)}, S, 2)")
    for s in range(starts.shape[1]):
        check_plan_inputs(obstacles, starts[:, s], goals)
    weights = as_vin_weights(model)  # a PyTorch VIN is read now, once for the whole batch
    parts = [
        plan_chunk(obstacles[sl], goals[sl], starts[sl], weights, corner_cutting, stats if stats is not None else {})
        for sl in chunk_slices(len(obstacles), chunk_size, progress)
    ]
    return PlanResult.concat(parts)


def plan_chunk(
    obstacles: np.ndarray,
    goals: np.ndarray,
    starts: np.ndarray,
    weights: VINWeights,
    corner_cutting: bool = True,
    stats: dict | None = None,
) -> PlanResult:
    """One chunk of `plan_maps`, on inputs already checked (contiguous `(b, N, N)` bool, `(b, 2)` and `(b, S, 2)`
    int64 in the grid) and `VINWeights`: the step of `VINPlanner.plan`'s loop. `stats`: near-tie counts, added to."""
    stats = {} if stats is None else stats
    b, s = starts.shape[0], starts.shape[1]
    n = obstacles.shape[1]
    p = FoldedVIN.from_weights(weights)
    # a rollout never visits a cell twice, so N * N cells bound its length (np.empty: untouched pages cost nothing)
    cells = np.empty((b * s, n * n, 2), dtype=np.int16)
    lengths = np.empty(b * s, dtype=np.int64)
    terms = np.empty(b * s, dtype=np.int8)
    over_maps(
        b,
        lambda lo, hi: _plan_kernel(
            lo,
            hi,
            obstacles,
            goals,
            starts,
            p.reward_w,
            p.reward_b,
            p.goal_value,
            p.q_w,
            p.w,
            p.fc,
            p.k,
            REL_MARGIN,
            bool(corner_cutting),
            ACTION_DELTAS,
            cells,
            lengths,
            terms,
        ),
        cost=_map_cost(p, n),
    )
    undecided = np.flatnonzero(terms == UNDECIDED)
    if len(undecided):  # rare: a rollout that stepped on a near tie is re-done with the reference's own decisions
        maps, map_of = np.unique(undecided // s, return_inverse=True)
        actions = exact_actions(weights, obstacles[maps], goals[maps])
        _redo_kernel(
            undecided,
            map_of,
            actions,
            obstacles,
            goals,
            starts,
            bool(corner_cutting),
            ACTION_DELTAS,
            cells,
            lengths,
            terms,
        )
        stats["near_tie_maps"] = stats.get("near_tie_maps", 0) + len(maps)
    stats["near_tie_rollouts"] = stats.get("near_tie_rollouts", 0) + len(undecided)
    return PlanResult.from_buffers(cells, lengths, terms)
