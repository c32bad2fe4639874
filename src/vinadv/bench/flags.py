"""Flags on suspicious benchmark results, as AutoAttack raises them: a flagged entry's figures are not to be trusted
at face value.

- `gradient_masking`: the planner's gradients hide its weakness from the white-box attack. Raised when the saliency
  gradient (of the log-probability of the planner's own path, with respect to the obstacles: `SaliencyAttack`) is
  zero, or not finite, on every one of the first maps of the suite (a gradient-free planner, `optimal`, has no
  gradient to mask and is not flagged); or, in a suite with the exhaustive search, when exhaustive harms far more
  maps than the gradient and ranking attacks: its harmful rate at one added cell is at least `suite.masking_min_rate`
  (10%) and more than `suite.masking_ratio` (3) times the larger of key-points' and saliency's.
- `non_deterministic`: two forward passes on the same maps differ (the logits, or the planned paths).
- `too_weak`: the clean success rate is under `suite.weak_clean_success` (50%): a planner that mostly fails on clean
  maps leaves few valid maps, and its robustness figures say little.
- `other_rules`: the planner's weights were trained on maps of another move rule than the suite's (`vin64`, trained
  with corner cutting, on the Moving AI suites, whose maps never cut corners): it runs under the suite's rule, which
  it never saw. Read from the training record of the zoo model of its weights (`trained_rules`); in an entry only
  where raised, so the entries of planners trained under their suite's rule are as they were.
"""

from __future__ import annotations

import numpy as np

from vinadv.attacks.strategies import AttackContext, SaliencyAttack
from vinadv.bench.suites import Suite
from vinadv.planners.interface import Planner

#: maps the gradient and determinism checks look at (the suite's first)
CHECK_MAPS = 16


def gradient_is_masked(planner: Planner, obstacles, starts, goals, corner_cutting: bool = True) -> bool | None:
    """Whether the saliency gradient is zero or not finite on every map (None: the planner has no gradient)."""
    if SaliencyAttack.gradient_module(planner) is None:  # a search planner's gradient is its path map's
        return None
    plans = planner.plan(obstacles, starts, goals, corner_cutting)
    ctx = AttackContext(obstacles, starts, goals, np.ones_like(obstacles), plans, planner, np.random.default_rng(0))
    scores = SaliencyAttack().candidate_scores(ctx)
    finite = np.isfinite(scores)
    return bool(not finite.all() or not scores[finite].any())


def differs_between_passes(planner: Planner, obstacles, starts, goals, corner_cutting: bool = True) -> bool:
    """Whether two forward passes on the same maps give different logits (a policy planner's; a search planner has
    none) or different paths."""
    if planner.capabilities.policy:
        first, second = planner.logits(obstacles, goals), planner.logits(obstacles, goals)
        if np.asarray(first).tobytes() != np.asarray(second).tobytes():
            return True
    a = planner.plan(obstacles, starts, goals, corner_cutting)
    b = planner.plan(obstacles, starts, goals, corner_cutting)
    return a.paths != b.paths or not np.array_equal(a.termination_names, b.termination_names)


def trained_rules(planner: Planner) -> dict | None:
    """The move rule of the maps the planner's weights were trained on, `{"corner_cutting": bool, "moves": str |
    None}`, from the training record of the zoo model of its weights (`vinadv.planners.registry.models`); None for a
    planner without weights, weights outside the zoo or a record that does not say."""
    from vinadv.planners.registry.models import read_zoo  # noqa: PLC0415 (light: hashes and JSON only)

    sha = planner.spec().get("weights_sha256")
    model = next((m for m in read_zoo().values() if sha is not None and m.sha256 == sha), None)
    record = model.training_record() if model is not None else None
    if not isinstance(record, dict):
        return None
    data = record.get("data") if isinstance(record.get("data"), dict) else {}
    cuts = record.get("corner_cutting", data.get("corner_cutting"))
    moves = record.get("moves", data.get("moves"))
    return None if not isinstance(cuts, bool) else {"corner_cutting": cuts, "moves": moves}


def _rule(corner_cutting: bool, moves: str | None) -> str:
    return f"{moves or 'its'} moves {'with' if corner_cutting else 'without'} corner cutting"


def raise_flags(suite: Suite, checks: dict, clean_success: float | None, attacks: dict) -> dict:
    """The entry's flags: {flag: {"raised": bool, "why": str}} from the `checks` made on the planner
    (`gradient_masked`, `non_deterministic`, `trained_rules`), the clean success rate and the per-attack figures."""
    masked = checks.get("gradient_masked")
    why = "the saliency gradient is zero or not finite on every checked map" if masked else ""
    exhaustive = attacks.get("add:exhaustive")
    if not masked and exhaustive is not None:
        rate = exhaustive["by_obstacles"][0]["harmful_rate"] or 0.0
        best = max(
            (
                attacks[k]["by_obstacles"][0]["harmful_rate"] or 0.0
                for k in ("add:key-points", "add:saliency")
                if k in attacks
            ),
            default=0.0,
        )
        if rate >= suite.masking_min_rate and rate > suite.masking_ratio * best:
            masked = True
            why = (
                f"exhaustive harms {rate:.1%} of the maps at one cell, over {suite.masking_ratio:g} times the best "
                f"gradient or ranking attack's {best:.1%}"
            )
    weak = clean_success is None or clean_success < suite.weak_clean_success
    other = {}
    trained = checks.get("trained_rules")
    if trained is not None and (
        trained["corner_cutting"] != suite.cuts_corners() or trained["moves"] not in (None, suite.movement())
    ):
        rules = (
            f"trained on maps of {_rule(trained['corner_cutting'], trained['moves'])}; run under the suite's rule, "
            f"{_rule(suite.cuts_corners(), suite.movement())}"
        )
        other = {"other_rules": {"raised": True, "why": rules}}
    return other | {
        "gradient_masking": {"raised": bool(masked), "why": why},
        "non_deterministic": {
            "raised": bool(checks.get("non_deterministic")),
            "why": "two forward passes on the same maps differ" if checks.get("non_deterministic") else "",
        },
        "too_weak": {
            "raised": bool(weak),
            "why": f"clean success under {suite.weak_clean_success:.0%}" if weak else "",
        },
    }
