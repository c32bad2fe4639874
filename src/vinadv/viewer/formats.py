"""How the viewer writes values: in the pages (`fmt_*`, Jinja globals) and in its JSON."""

from __future__ import annotations

import math


def none_if_nan(value) -> float | None:
    return None if value is None or (isinstance(value, float) and math.isnan(value)) else float(value)


def none_if_negative(value) -> int | None:
    return None if value is None or value < 0 else int(value)


def effort_ratio(expansions_o, expansions_a) -> float | None:
    """The effort ratio `expansions_a / expansions_o` (DESIGN.md "Search effort"), None without both counts."""
    if not expansions_o or not expansions_a:
        return None
    return expansions_a / expansions_o


def pair_row_json(row: dict, humans: list[dict]) -> dict:
    """A row of the pair grid (`Store.page_pairs`) as the grid and its JSON show it."""
    return {
        "pair_index": int(row["pair_index"]),
        "label": row["label"],
        "attack": bool(row["attack"]),
        "label_source": row["label_source"],
        "score": none_if_nan(row["score"]),
        "dh": none_if_negative(row["dh"]),
        "dv": none_if_negative(row["dv"]),
        "term_o": row["term_o"],
        "term_a": row["term_a"],
        "human_labels": humans,
        "harm": row["harm"],
        "regret_o": none_if_nan(row["regret_o"]),
        "regret_a": none_if_nan(row["regret_a"]),
        "expansions_o": row["expansions_o"],
        "expansions_a": row["expansions_a"],
        "effort_ratio": effort_ratio(row["expansions_o"], row["expansions_a"]),
    }


def run_planner(run: dict) -> str:
    """The planner a run's pairs were planned by (its config's `planner`; `vin` where the config names none)."""
    return (run.get("config") or {}).get("planner") or "vin"


def run_json(run: dict) -> dict:
    return {
        "id": int(run["id"]),
        "name": run["name"],
        "created": run["created"].isoformat() + "Z",
        "status": run["status"],
        "attack": run["attack"],
        "planner": run["planner"],
        "classifier": run["classifier"],
        "seed": run["seed"],
        "n_pairs": run["n_pairs"],
        "counts": run["counts"],
        "n_valid": run["n_valid"],
        "n_success": run["n_success"],
        "success_rate": run["success_rate"],
        "harm_counts": run["harm_counts"],
        "harmful_rate": run["harmful_rate"],
        "harmful_rate_low": run["harmful_rate_low"],
        "harmful_rate_high": run["harmful_rate_high"],
    }


def fmt_score(value) -> str:
    return "—" if value is None else f"{value:.3f}"


def fmt_cost(value) -> str:
    """`1.414`; float noise around 0 (a regret of -2e-15) as `0.000`, not `-0.000`."""
    return "—" if value is None else f"{round(float(value), 3) + 0.0:.3f}"


def fmt_dist(value) -> str:
    return "—" if value is None else str(value)


def fmt_ratio(value) -> str:
    return "—" if value is None else f"{value:.2f}x"


def fmt_pct(value) -> str:
    return "—" if value is None else f"{100 * value:.1f}%"


def fmt_pct_ci(rate, low, high) -> str:
    """A rate with its Wilson 95% interval in points: `57.7% [47.9, 67.0]` ("—" without a rate)."""
    if rate is None or low is None or high is None:
        return fmt_pct(rate)
    return f"{fmt_pct(rate)} [{100 * low:.1f}, {100 * high:.1f}]"
