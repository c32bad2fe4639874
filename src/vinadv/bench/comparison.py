"""What the per-map outcomes of `vinadv.bench_entry/2` entries (`vinadv.bench.outcomes`) allow beyond their figures:
rows per family of maps, a paired test of two planners on the same maps, and bootstrap intervals of the means.

- Families (`family_rows`): a data suite that joins several files (`vinadv.bench.suites.DataSuite`; the MP suites
  join six families) takes each file's maps in order, so map i's family follows from its index (`family_spans`). Per
  family: the clean success and, at each k, the worst-case harmful rate over the family's valid maps, each with its
  Wilson 95% interval (`vinadv.intervals`).
- Paired test (`mcnemar`, `compare_entries`): two entries of one suite (the same checksum: the same maps) are
  compared map by map on the worst-case harmful verdict at each k (`outcomes.worst_case_within`), over the maps valid
  for both planners (a pair was made and both reach the goal on the clean map: a map one planner fails clean is not
  one it could be harmed on). McNemar's exact test: under the null that the two planners are equally robust, each
  discordant map (harmful for one planner only) is harmful for A or for B with probability 1/2, so the count of maps
  harmful for A only is binomial(discordant, 1/2); the p-value is two-sided. `ALPHA` is the level at which the
  leaderboard says one is more robust than the other.
- Means (`mean_intervals`): the worst-case mean regret at each k and the clean mean regret, and for a search
  planner's entry the mean worst effort ratio at each k (`per_map.worst_effort`: each valid map's largest effort ratio
  over the attacks of at most k edits) and its clean Exp and cost ratio (`per_map.clean.exp`, `cost_ratio`), each
  with its seeded percentile bootstrap interval over the maps that have a
  value (`vinadv.intervals.bootstrap_mean_interval`): the same entry gives the same numbers.

A `vinadv.bench_entry/1` entry holds no per-map outcomes: none of this can be computed from it ("needs a format 2
entry").
"""

from __future__ import annotations

import math
import re
from fractions import Fraction
from pathlib import Path

import numpy as np

from vinadv import display
from vinadv.bench.outcomes import exact_mean, outcome, worst_case_within
from vinadv.bench.suites import ENTRY_FORMAT_2, SUITES, DataSuite
from vinadv.errors import InputError
from vinadv.intervals import bootstrap_mean_interval, interval_fields
from vinadv.robustness import MapOutcomes

#: the level of the paired test: below it, the leaderboard says one planner is more robust than the other
ALPHA = 0.05
#: what the readers say of an entry without per-map outcomes
NEEDS_FORMAT_2 = "needs a format 2 entry"


def entry_suite(entry: dict):
    """The registered suite of `entry` (`vinadv.bench.suites.SUITES`), or None where its name or checksum is not one
    this vinadv has (its maps' order is then unknown)."""
    suite = SUITES.get(entry["suite"]["name"])
    return suite if suite is not None and suite.checksum == entry["suite"]["checksum"] else None


def has_outcomes(entry: dict) -> bool:
    """Whether `entry` holds per-map outcomes (`vinadv.bench_entry/2`)."""
    return entry.get("format") == ENTRY_FORMAT_2 and isinstance(entry.get("per_map"), dict)


def worst_per_map(entry: dict) -> list[MapOutcomes]:
    """Each map's worst case at k = 1 .. the suite's largest k (`outcomes.worst_case_within`) from the per-map
    outcomes of `entry` (a format 2 entry)."""
    per_k: dict[int, list[MapOutcomes]] = {}
    for records in entry["per_map"]["attacks"].values():
        for record in records:
            per_k.setdefault(record["k"], []).append(outcome(record))
    return worst_case_within([per_k.get(k, []) for k in range(1, max(per_k) + 1)])


#: the MP dataset's file names: `<family>_<size>_<moves>_c<k>.npz`; the family is what comes before the size
_MPD_NAME = re.compile(r"_\d+_(moore|neumann)_c\d+$")


def family_spans(suite) -> list[tuple[str, int, int]]:
    """`[(family, first map, end)]` of a data suite that joins several files (each file's maps in order, its family
    named by the file: `alternating_gaps` for `alternating_gaps_032_moore_c8.npz`); [] for any other suite."""
    if not isinstance(suite, DataSuite) or len(suite.files) < 2:
        return []
    spans, start = [], 0
    for file in suite.files:
        spans.append((_MPD_NAME.sub("", Path(file.name).stem), start, start + file.maps))
        start += file.maps
    return spans


def family_rows(entry: dict) -> list[dict]:
    """Per family of the entry's suite (`family_spans`; [] for a suite of one family, an unknown suite or an entry
    without per-map outcomes): `family`, `maps`, `clean_success` (`reached` of `maps`) and `worst_case`, per k the
    harmful rate over the family's valid maps (`harmful`, `valid`), each rate with its Wilson interval."""
    suite = entry_suite(entry)
    if suite is None or not has_outcomes(entry):
        return []
    reached = np.array(entry["per_map"]["clean"]["reached"], dtype=bool)
    worst = worst_per_map(entry)
    out = []
    for family, lo, hi in family_spans(suite):
        row = {"family": family, "maps": hi - lo, "reached": int(reached[lo:hi].sum())}
        row["clean_success"] = row["reached"] / row["maps"]
        row.update(interval_fields("clean_success", row["reached"], row["maps"]))
        row["worst_case"] = []
        for k, o in enumerate(worst, start=1):
            harmful, valid = int(o.harmful[lo:hi].sum()), int(o.valid[lo:hi].sum())
            rate = harmful / valid if valid else None
            row["worst_case"].append(
                {"k": k, "harmful": harmful, "valid": valid, "harmful_rate": rate}
                | interval_fields("harmful_rate", harmful, valid)
            )
        out.append(row)
    return out


def mcnemar(a_only: int, b_only: int) -> float:
    """The two-sided p-value of McNemar's exact test on `a_only` and `b_only` discordant maps: the binomial test of
    `a_only` successes in `n = a_only + b_only` trials at 1/2, `min(1, 2 P(X <= min(a_only, b_only)))` (the
    distribution is symmetric: the outcomes at most as likely as the one seen are the two tails), in exact integer
    arithmetic (1.0 without a discordant map). scipy's `binomtest` gives the same, after a 3-second import."""
    if a_only < 0 or b_only < 0:
        raise InputError(f"discordant counts must be >= 0, got {a_only} and {b_only}", "a_only")
    n = a_only + b_only
    tail = sum(math.comb(n, i) for i in range(min(a_only, b_only) + 1))
    return min(1.0, float(Fraction(2 * tail, 2**n)))


def paired_counts(a: MapOutcomes, b: MapOutcomes) -> dict:
    """McNemar's counts of two planners' worst cases on the same maps, over the maps valid for both (`maps`):
    `a_only` (harmful for A, not for B), `b_only`, `both`, `neither`, and the p-value (`mcnemar`)."""
    if len(a.valid) != len(b.valid):
        raise InputError(f"the entries hold {len(a.valid)} and {len(b.valid)} maps: not the same maps", "b")
    shared = a.valid & b.valid
    ha, hb = a.harmful & shared, b.harmful & shared
    counts = {
        "maps": int(shared.sum()),
        "a_only": int((ha & ~hb).sum()),
        "b_only": int((hb & ~ha).sum()),
        "both": int((ha & hb).sum()),
        "neither": int((shared & ~ha & ~hb).sum()),
    }
    return {**counts, "p_value": mcnemar(counts["a_only"], counts["b_only"])}


def verdict(test: dict) -> str:
    """`more robust` (A is harmful on fewer of the discordant maps, p < `ALPHA`), `less robust`, or `not
    distinguishable`."""
    if test["p_value"] >= ALPHA:
        return "not distinguishable"
    return "more robust" if test["a_only"] < test["b_only"] else "less robust"


def compare_entries(a: dict, b: dict) -> list[dict]:
    """McNemar's test of entry `a` against entry `b` at each k (`paired_counts`, with `verdict`: what A is against
    B); InputError where they are not two format 2 entries of one suite (the same checksum)."""
    for name, e in (("a", a), ("b", b)):
        if not has_outcomes(e):
            raise InputError(f"entry {name.upper()}: a {e.get('format')} entry, {NEEDS_FORMAT_2}", name)
    if a["suite"] != b["suite"]:
        raise InputError(
            f"the entries are of two suites ({a['suite']['name']} {a['suite']['checksum'][:12]}, "
            f"{b['suite']['name']} {b['suite']['checksum'][:12]}): a paired test needs the same maps",
            "b",
        )
    out = []
    for k, (wa, wb) in enumerate(zip(worst_per_map(a), worst_per_map(b)), start=1):
        test = paired_counts(wa, wb)
        out.append({"k": k, **test, "verdict": verdict(test)})
    return out


def mean_intervals(entry: dict) -> dict:
    """The means of `entry` that its per-map values allow, each with its bootstrap interval over the maps that have a
    value (`mean`, `low`, `high`, `maps`): `clean_regret` (the clean paths that reach the goal) and `worst_regret`,
    per k, the worst case's regret (the valid maps whose worst adversarial path reaches the goal); where the entry
    holds efforts, `worst_effort`, per k, each valid map's largest effort ratio over the attacks of at most k edits;
    where it holds a search planner's per-map protocol values, `clean_exp` (Exp, over every map) and
    `clean_cost_ratio` (over the maps whose clean path reaches the goal). {} for an entry without per-map outcomes."""
    if not has_outcomes(entry):
        return {}

    def mean(values) -> dict:
        x = np.array([np.nan if v is None else v for v in values], dtype=np.float64)
        x = x[~np.isnan(x)]
        low, high = bootstrap_mean_interval(x)
        return {"mean": exact_mean(x), "low": low, "high": high, "maps": len(x)}

    clean = entry["per_map"]["clean"]
    regrets = [r if ok else None for r, ok in zip(clean["regret"], clean["reached"])]
    worst = [{"k": k, **mean(o.regret)} for k, o in enumerate(worst_per_map(entry), start=1)]
    out = {"clean_regret": mean(regrets), "worst_regret": worst}
    for name in ("exp", "cost_ratio"):  # a search planner's clean protocol, where the entry holds its maps' values
        if name in clean:
            out[f"clean_{name}"] = mean(clean[name])
    if "worst_effort" in entry["per_map"]:  # a search planner's: each map's largest effort ratio at each k
        out["worst_effort"] = [{"k": k, **mean(v)} for k, v in enumerate(entry["per_map"]["worst_effort"], start=1)]
    return out


def vs_next(a: dict, b: dict) -> dict | None:
    """The leaderboard's paired test of a row's entry `a` against the next row's `b` at k = 1 (the rank's key:
    `compare_entries`), or None where either holds no per-map outcomes or their suites differ."""
    if not (has_outcomes(a) and has_outcomes(b)) or a["suite"] != b["suite"]:
        return None
    return compare_entries(a, b)[0]


def p_text(p: float) -> str:
    """A p-value as shown: `p < 0.001`, or `p = 0.041`."""
    return "p < 0.001" if p < 0.001 else f"p = {p:.3f}"


def family_table(rs: list[dict], name) -> tuple[list[str], list[list[tuple[str, str]]]]:
    """The per-family table of one suite's rows (`vinadv.bench.comparison.family_rows`; ([], []) where no row has
    families; `name(row)`: the row's name): the titles (planner, then each family) and per row with families its
    cells, each family's `(worst-case harmful at the largest k, its interval and the clean success)`."""
    with_families = [r for r in rs if r.get("families")]
    if not with_families:
        return [], []
    titles = ["planner", *(f["family"] for f in with_families[0]["families"])]
    table = []
    for r in with_families:
        cells = [(name(r), "")]
        for f in r["families"]:
            worst = f["worst_case"][-1]
            interval = display.points(worst["harmful_rate_low"], worst["harmful_rate_high"])
            cells.append(
                (display.percent(worst["harmful_rate"]), f"{interval} · clean {display.percent(f['clean_success'])}")
            )
        table.append(cells)
    return titles, table


#: what the per-family table says (`family_table`)
FAMILY_NOTE = (
    "By family: the worst-case harmful rate at the suite's largest k over each family's valid maps, with its Wilson "
    "95% interval, and the family's clean success (computed from the entries' per-map outcomes: v2 entries only). "
    "`vinadv bench leaderboard --json` holds every k."
)
