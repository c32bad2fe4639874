"""The VIN's `fc` at one cell as PyTorch computes it: its summation tree, read off PyTorch with exact probes
(`fc_order`), and the logits summed along it in float32 (`replay_fc`), fused multiply-adds rounded once (`fma32`).
"""

from __future__ import annotations

import numpy as np

from vinadv.planners.vin.replay.cache import CACHE, torch_threads_now
from vinadv.planners.vin.replay.orders import PROBES

__all__ = ["MAX_FC_WIDTH", "fc_order", "fma32", "replay_fc"]

#: the widest `fc` (l_q) whose summation tree `fc_order` measures (its probes grow as l_q^3 / A); wider ones: PyTorch
MAX_FC_WIDTH = 64


def fc_order(l_q: int, n_actions: int) -> tuple[tuple, bool] | None:
    """How PyTorch's `F.linear((1, l_q), (A, l_q))` (the VIN's `fc` at one cell) sums the l_q products of each
    logit: `(tree, fused)`, a binary tree over the product indices (nested pairs, leaves ints) and whether each add
    with a product beside it is a fused multiply-add (the product of the higher index, where both are products);
    None if no such tree reproduces PyTorch bit for bit. Measured once per (l_q, A, PyTorch threads).

    The tree comes from exact probes: with products +B, -B and 1 at indices i, j and k (B = 2^30, where 1 is below
    half an ulp) the logit is 1 exactly when i and j meet before k, else 0; those relations give every subtree."""
    key = (l_q, n_actions, torch_threads_now())
    if key not in CACHE.fc_orders:
        CACHE.fc_orders[key] = CACHE.measured("fc_order", key, lambda: _measure_fc_order(l_q, n_actions), _tree_of)
    return CACHE.fc_orders[key]


def _tree_of(value) -> tuple[tuple, bool]:
    """`(tree, fused)` back from JSON lists."""

    def tree(node):
        return node if isinstance(node, int) else tuple(tree(child) for child in node)

    return tree(value[0]), bool(value[1])


def _linear(q: np.ndarray, w: np.ndarray) -> np.ndarray:
    import torch
    import torch.nn.functional as F

    with torch.no_grad():
        return F.linear(torch.from_numpy(q)[None], torch.from_numpy(w))[0].numpy()


def _measure_fc_order(l_q: int, n_actions: int) -> tuple[tuple, bool] | None:
    if l_q > MAX_FC_WIDTH:
        return None
    big = np.float32(2.0**30)
    ones = np.ones(l_q, np.float32)
    # the leaves under the subtree where i and j meet: i, j and every k that does not survive their cancelling;
    # one probe per logit (each logit is summed on its own; a wrong tree fails the random check below anyway)
    subtrees = {frozenset([k]) for k in range(l_q)} | {frozenset(range(l_q))}
    for i in range(l_q):
        for j in range(i + 1, l_q):
            members, others = {i, j}, [k for k in range(l_q) if k not in (i, j)]
            for lo in range(0, len(others), n_actions):
                ks = others[lo : lo + n_actions]
                w = np.zeros((n_actions, l_q), np.float32)
                w[:, i], w[:, j] = big, -big
                w[np.arange(len(ks)), ks] = 1.0
                logits = _linear(ones, w)[: len(ks)]
                if not np.all((logits == 0.0) | (logits == 1.0)):
                    return None
                members.update(k for k, y in zip(ks, logits) if y == 0.0)
            subtrees.add(frozenset(members))
    tree = _build_tree(frozenset(range(l_q)), subtrees)
    if tree is None:
        return None
    rng = np.random.default_rng(2)
    probes = [
        (
            (scale * rng.standard_normal(l_q)).astype(np.float32),
            rng.standard_normal((n_actions, l_q)).astype(np.float32),
        )
        for scale in np.logspace(-2, 2, PROBES)
    ]
    found = [
        fused
        for fused in (True, False)
        if all(np.array_equal(replay_fc(w, q, tree, fused), _linear(q, w)) for q, w in probes)
    ]
    return (tree, found[0]) if len(found) == 1 else None


def _build_tree(leaves: frozenset, subtrees: set[frozenset]):
    """The binary tree whose subtrees' leaf sets are `subtrees` under `leaves`, as nested pairs; None if they are not
    the subtrees of one binary tree."""
    if len(leaves) == 1:
        return next(iter(leaves))
    inside = [t for t in subtrees if t < leaves]
    children = [t for t in inside if not any(t < u for u in inside)]
    if len(children) != 2 or children[0] | children[1] != leaves or children[0] & children[1]:
        return None
    first, second = sorted(children, key=min)
    left, right = _build_tree(first, subtrees), _build_tree(second, subtrees)
    return None if left is None or right is None else (left, right)


def replay_fc(w: np.ndarray, q: np.ndarray, tree, fused: bool) -> np.ndarray:
    """The logits `w (A, l_q) @ q (l_q,)` in float32, summed along `tree` (`fc_order`): `(A,)` float32."""

    def value(node, a):
        if isinstance(node, int):
            return np.float32(w[a, node] * q[node])
        left, right = node
        if fused and (isinstance(left, int) or isinstance(right, int)):
            leaf, other = (right, left) if isinstance(right, int) else (left, right)
            return fma32(w[a, leaf], q[leaf], value(other, a))
        return np.float32(value(left, a) + value(right, a))

    return np.array([value(tree, a) for a in range(w.shape[0])], dtype=np.float32)


def fma32(a: np.float32, b: np.float32, c: np.float32) -> np.float32:
    """a * b + c rounded once to float32 (a fused multiply-add): the float64 product is exact, the float64 sum is
    made exact by its rounding error (TwoSum), and only a sum landing exactly halfway between two float32 needs
    that error to round the right way."""
    p, c = float(a) * float(b), float(c)
    s = p + c
    t = s - p
    err = (p - (s - t)) + (c - t)
    r = np.float32(s)
    if err != 0.0 and float(r) != s:
        other = np.nextafter(r, np.float32(np.inf) if s > float(r) else np.float32(-np.inf))
        if abs(float(other) - s) == abs(float(r) - s):  # s is a tie between r and other: the error decides
            r = other if (err > 0) == (float(other) > s) else r
    return np.float32(r)
