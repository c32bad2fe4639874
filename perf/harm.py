"""Labelling throughput: today's rule labeller against the rule labeller plus harm (vinadv.classify.harm).

    nice .venv/bin/python perf/harm.py [--pairs PAIRS.npz] [--n 100000] [--maps 10000] [--attack near-path]
        [--json]

Without --pairs it makes real pairs: `--maps` generated 28x28 maps attacked by `--attack` with the shipped VIN
(one pair per map), tiled to `--n` pairs (tiled whole, so no two neighbouring pairs share an original map and
harm gains nothing from sharing a search). Timed side by side in this run, taking turns, best of `--rounds`:
- `rule`: the rule labeller (`label_batch`) of all pairs;
- `rule + harm, from scratch`: plus `pair_harm` searching every original map (what `vinadv identify` does);
- `rule + harm, generator's expert paths`: plus `pair_harm` given the original maps' expert paths the generator
  already computed (what `vinadv run` does): only adversarial maps whose expert route the obstacle blocks are
  searched.
"""

from __future__ import annotations

import argparse
import json

import numba
import numpy as np

from common import add_output_arguments, timed_side_by_side  # perf/common.py
from vinadv.attacks.pairs import PairSet
from vinadv.attacks.strategies import make_attack
from vinadv.classify import PathPairBatch, label_batch
from vinadv.classify.harm import pairset_harm
from vinadv.grid.generator import generate_maps
from vinadv.grid.shortest_paths import expert_paths
from vinadv.planners.vin.weights import load_vin


def make_pairs(n_maps: int, attack: str, seed: int = 0):
    """Real attack pairs on generated maps, and the generator's expert paths of each pair's original map."""
    maps = generate_maps(n_maps, 28, seed=seed, n_starts=1)
    result = make_attack(attack, per_map=1, seed=seed).attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, load_vin(None, size=28)
    )
    pairs = result.pairs
    return pairs, (maps.expert_costs[pairs.map_index, 0], maps.expert.take(pairs.map_index))


def tile(pairs, expert, n: int):
    """`pairs` (and their expert data) repeated whole to `n` pairs."""
    idx = np.arange(n) % len(pairs)
    return pairs.take(idx), (expert[0][idx], expert[1].take(idx))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", help="a real pairs file (vinadv.pairs/1) instead of generated pairs")
    parser.add_argument("--n", type=int, default=100_000, help="pairs to time (default 100000)")
    parser.add_argument("--maps", type=int, default=10_000, help="maps generated and attacked (default 10000)")
    parser.add_argument("--attack", default="near-path", help="attack strategy for generated pairs")
    add_output_arguments(parser, rounds=5)
    args = parser.parse_args(argv)

    if args.pairs:
        pairs = PairSet.load(args.pairs)
        costs, paths = expert_paths(pairs.obstacles_o, pairs.goals, pairs.starts[:, None], pairs.corner_cutting)
        source, expert = args.pairs, (costs[:, 0], paths)
    else:
        pairs, expert = make_pairs(args.maps, args.attack)
        source = f"{len(pairs)} {args.attack} pairs on {args.maps} generated 28x28 maps (shipped VIN)"
    pairs, expert = tile(pairs, expert, args.n)

    def rule():
        return label_batch(PathPairBatch.from_pairs(pairs)).labels

    def rule_harm_scratch():
        return pairset_harm(pairs, rule())

    def rule_harm_given():
        return pairset_harm(pairs, rule(), expert_o=expert)

    for fn in (rule, rule_harm_scratch, rule_harm_given):  # compile and warm up
        fn()
    (t_rule, t_scratch, t_given), (labels, scratch, given) = timed_side_by_side(
        (rule, rule_harm_scratch, rule_harm_given), args.rounds
    )
    same = all(np.array_equal(getattr(scratch, f), getattr(given, f)) for f in ("harm", "expert_label"))
    blocked = float(np.mean(given.expert_label != "UcP"))
    out = {
        "pairs": len(pairs),
        "source": source,
        "numba_threads": numba.get_num_threads(),
        "rule_pairs_per_s": len(pairs) / t_rule,
        "rule_harm_scratch_pairs_per_s": len(pairs) / t_scratch,
        "rule_harm_given_pairs_per_s": len(pairs) / t_given,
        "scratch_over_rule": t_scratch / t_rule,
        "given_over_rule": t_given / t_rule,
        "adversarial_searched_fraction": blocked,
        "same_result": same,
        "label_x_harm": {
            lab: {h: int(np.sum((labels == lab) & (given.harm == h))) for h in ("harmful", "harmless")}
            for lab in ("UrP", "UcP", "DP", "FP")
        },
    }
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"{out['pairs']:,} pairs: {source}; numba threads {out['numba_threads']}")
    print(f"{'labelling':<42}{'s':>8}{'pairs/s':>12}{'x rule':>8}")
    for name, t in (
        ("rule labeller", t_rule),
        ("rule + harm, from scratch", t_scratch),
        ("rule + harm, generator's expert paths", t_given),
    ):
        print(f"{name:<42}{t:>8.3f}{len(pairs) / t:>12,.0f}{t / t_rule:>8.2f}")
    print(f"adversarial maps searched (expert route blocked): {blocked:.1%}; both harm variants agree: {same}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
