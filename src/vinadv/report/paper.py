"""The paper's numbers (Wang et al., tables 4-7 and section 5.2), shown beside ours in the report."""

from __future__ import annotations

#: table 4: pairs per category out of 5,000
TABLE4 = {"UrP": 1632, "FP": 204, "DP": 1076, "UcP": 2088}
#: table 5: training time in seconds (70% of 5,000 pairs, balanced, 10 epochs for the networks)
TRAINING_S = {"svm": 46.0, "cnn": 474.0, "mlp": 105.0}
#: table 6: test accuracy (balanced training)
ACCURACY = {"svm": 0.97, "cnn": 0.76, "mlp": 0.68}
#: fig. 9: the SVM's accuracy by training set
SVM_ACCURACY = {"imbalanced": 0.91, "balanced": 0.97}
#: table 7: seconds to identify 100 pairs
PROCESSING_S = {"training": 0.22, "manual": 300.0}
#: the epochs the paper trains its CNN and MLP for
EPOCHS = 10
ENV = "Intel i7-4510U, 8 GB, Windows 10, Python 2.7"
#: the paper's setting: its planner (the VIN, any weights), map side, movement model and obstacles added per pair
SETTING = {"planner": "vin", "size": 28, "moves": "octile", "obstacles": 1}


def papers_setting(info: dict) -> str | None:
    """None when the run `info` (a `Store.run_info` row) is in the paper's setting (`SETTING`: the VIN, not one of
    its variants, on 28x28 `octile` maps with corner cutting, one obstacle added per pair), so the paper's numbers
    belong beside its own; else why not, in words. A setting the run did not record (an identified pairs file's
    obstacles) counts as the paper's."""
    config = info.get("config") or {}
    spec = config.get("planner_spec") or {}
    planner = spec.get("name") or config.get("planner") or SETTING["planner"]
    size = config.get("size") or spec.get("size")
    obstacles = config.get("obstacles") or (config.get("params") or {}).get("obstacles") or 1
    edit = config.get("edit") or "add"
    differs = [
        f"planner {planner!r}, not the paper's VIN" if planner != SETTING["planner"] else None,
        f"{size}x{size} maps, not 28x28" if size is not None and size != SETTING["size"] else None,
        f"{info.get('moves')} moves, not octile" if info.get("moves", "octile") != SETTING["moves"] else None,
        "no corner cutting" if not config.get("corner_cutting", True) else None,
        f"{obstacles} obstacles per pair, not 1" if obstacles != SETTING["obstacles"] else None,
        "obstacles removed, not added" if edit != "add" else None,
    ]
    differs = [d for d in differs if d]
    return "; ".join(differs) if differs else None
