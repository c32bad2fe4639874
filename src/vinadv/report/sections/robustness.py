"""Robustness benchmarks."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from vinadv.intervals import figure_intervals, interval_columns
from vinadv.report.data import Context, Figure, Table

#: the worst case over the strategies, as `vinadv.robustness.WORST_CASE` names it (not imported: no torch here)
WORST_CASE = "worst case"


@dataclass(frozen=True)
class Benchmark:
    """One stored robustness benchmark (`vinadv robustness`): what was measured and its figures, as stored
    (`worst`: the worst case by k, `by_strategy`: {strategy: figures by k}; figures as `Figures.to_dict`, with their
    rates' intervals computed from the counts: `with_intervals`)."""

    id: int | None
    created: str
    planner: str
    weights: str | None
    n: int
    size: int
    maps_seed: int
    objective: str
    strategies: tuple[str, ...]
    clean_success: float | None
    clean_regret: float | None
    worst: list[dict]
    by_strategy: dict[str, list[dict]]
    seconds: dict[str, float]
    edit: str = "add"
    run_name: str | None = None  # `vinadv robustness --name`
    maps_file: str | None = None  # the maps file (None: the generator's maps of `maps_seed`)
    maps_sha256: str | None = None

    @property
    def name(self) -> str:
        """The benchmark in a legend: its run name, the planner's full spec, weights (first 8 hex digits), the maps
        file's name where it came from one, `removal` for a benchmark that frees obstacles, and id: two runs of one
        planner on two maps files read apart."""
        named = f"{self.run_name}: " if self.run_name else ""
        weights = f" {self.weights[:8]}" if self.weights else ""
        maps = f" on {Path(self.maps_file).name}" if self.maps_file else ""
        removal = " removal" if self.edit == "remove" else ""
        return f"{named}{self.planner}{weights}{maps}{removal}" + (f" (#{self.id})" if self.id is not None else "")

    @property
    def maps(self) -> str:
        """Where the maps came from: the maps file's name and SHA-256 (first 12 hex digits), or the seed."""
        if self.maps_file:
            return f"{Path(self.maps_file).name} ({(self.maps_sha256 or '')[:12]})"
        return f"seed {self.maps_seed}"

    def strategy_name(self, name: str) -> str:
        """A strategy (or the worst case) in the table: `(remove)` added where the benchmark frees obstacles."""
        return f"{name} (remove)" if self.edit == "remove" else name


@dataclass
class RobustnessData:
    """The robustness benchmarks of the database, oldest first (none: `benchmarks` empty, nothing else)."""

    benchmarks: list[Benchmark]
    table: Table | None = None
    figure: Figure | None = None

    def tables(self) -> list[Table]:
        return [] if self.table is None else [self.table]

    def figures(self) -> list[Figure]:
        return [] if self.figure is None else [self.figure]

    @property
    def max_k(self) -> int:
        return max([0] + [len(b.worst) for b in self.benchmarks])


def with_intervals(by_k: list[dict]) -> list[dict]:
    """Figures by k, each with its rates' Wilson 95% intervals (`{rate}_low`, `{rate}_high`), computed from the
    counts (`vinadv.intervals.figure_intervals`): a benchmark stored before intervals has them too; and the mean
    regret's bootstrap interval as stored (None for a benchmark stored before it: it needs the per-map regrets)."""
    return [{"mean_regret_low": None, "mean_regret_high": None, **f, **figure_intervals(f)} for f in by_k]


def robustness_section(rows: list[dict], out: Path) -> RobustnessData:
    """The robustness section of `rows`, robustness benchmarks as `Store.read_robustness` returns them (`id` None for
    one not stored): the comparison table, its CSV (every strategy and the worst case at every k) and the curves."""
    from vinadv.report import figures  # noqa: PLC0415 (Matplotlib: drawn when gathered)

    benchmarks = []
    for row in rows:
        result, settings = row["result"], row["settings"]
        benchmarks.append(
            Benchmark(
                id=row.get("id"),
                created=str(row.get("created") or ""),
                planner=str(settings.get("planner") or row["planner"]),  # the full spec (older rows: the name)
                weights=row.get("weights_checksum"),
                n=int(settings["n"]),
                size=int(settings["size"]),
                maps_seed=int(settings["maps_seed"]),
                objective=str(settings["objective"]),
                strategies=tuple(settings["strategies"]),
                clean_success=result["clean"]["success_rate"],
                clean_regret=result["clean"]["mean_regret"],
                worst=with_intervals(result["overall"]),
                by_strategy={name: with_intervals(s["by_obstacles"]) for name, s in result["strategies"].items()},
                seconds={
                    **{name: s["seconds"] for name, s in result["strategies"].items()},
                    "total": result["seconds"],
                },
                edit=str(settings["edit"]),
                run_name=settings.get("name"),
                maps_file=settings.get("maps"),
                maps_sha256=settings.get("maps_sha256"),
            )
        )
    data = RobustnessData(benchmarks=benchmarks)
    if not benchmarks:
        return data
    keys = (
        "valid",
        "broken",
        *interval_columns("paper_success_rate"),
        "harmful",
        *interval_columns("harmful_rate"),
        "reached",
        *interval_columns("mean_regret"),
        "effort_harmful",
        *interval_columns("effort_harmful_rate"),
    )
    data.table = Table(
        "robustness.csv",
        (
            "benchmark",
            "name",
            "planner",
            "weights_sha256",
            "maps_file",
            "maps_sha256",
            "maps",
            "size",
            "maps_seed",
            "objective",
            "clean_success",
            "strategy",
            "k",
            *keys,
            "seconds",
        ),
        [
            [
                b.id,
                b.run_name,
                b.planner,
                b.weights,
                b.maps_file,
                b.maps_sha256,
                b.n,
                b.size,
                b.maps_seed,
                b.objective,
                b.clean_success,
                b.strategy_name(name),
                f["k"],
                *(f.get(key) for key in keys),  # the effort figures: a planner that reports expansions only
                b.seconds.get(name, b.seconds["total"]),
            ]
            for b in benchmarks
            for name, by_k in (*b.by_strategy.items(), (WORST_CASE, b.worst))
            for f in by_k
        ],
    )
    data.figure = Figure(
        tuple(figures.robustness_curves([(b.name, b.worst) for b in benchmarks], out / "fig_robustness")),
        "Robustness curves: the share of valid maps that k added obstacles make harmful (left) or break by the "
        "paper's definition, UrP or FP (right), worst case over the strategies of each benchmark; the bands are "
        "95% Wilson intervals over the valid maps.",
        "robustness curves",
        880,
    )
    return data


def gather(ctx: Context) -> RobustnessData:
    return robustness_section(ctx.store.read_robustness(), ctx.out)
