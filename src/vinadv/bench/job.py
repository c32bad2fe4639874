"""`vinadv bench run` as a job: `BenchConfig` (a suite by name, the planner by its spec), `run(config, executor)`
and `BenchResult` (the entry, or a part of it, `to_dict()`; `vinadv.bench.scoring`, `vinadv.bench.parts`)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

from vinadv.bench.scoring import entry_json, run_bench, run_part, submission_fields
from vinadv.bench.suites import Suite, get_suite
from vinadv.executor import LOCAL, Executor


@dataclass(frozen=True)
class BenchConfig:
    """What determines a bench entry: the suite (`vinadv.bench.suites`, by name), the planner's spec and weights,
    the folder of a data suite's files (`data`), and how the entry is shared (an entry of format 2: its display name,
    authors, paper and code links, whether it is submitted from outside; `vinadv.bench.scoring.submission_fields`);
    checked when made (an unknown suite, a link that is not http or https: InputError naming it)."""

    suite: str
    planner: str | None = None
    weights: str | None = None
    data: str | None = None
    display_name: str | None = None
    authors: tuple[str, ...] = ()
    paper: str | None = None
    code: str | None = None
    external: bool = False

    def __post_init__(self):
        object.__setattr__(self, "authors", tuple(self.authors))
        submission_fields(get_suite(self.suite), self.submission)

    @property
    def submission(self) -> dict:
        """The entry's submission fields."""
        return {
            "display_name": self.display_name,
            "authors": list(self.authors),
            "paper": self.paper,
            "code": self.code,
            "external": self.external,
        }

    def to_dict(self) -> dict:
        return asdict(self)

    @property
    def frozen_suite(self) -> Suite:
        return get_suite(self.suite)


@dataclass
class BenchResult:
    """A bench entry (`vinadv.bench.scoring.make_entry`), or a part of one (`vinadv.bench.parts.make_part`)."""

    entry: dict

    def to_dict(self) -> dict:
        return self.entry

    def json(self) -> str:
        """The entry as written (`entry_json`), or the part (`vinadv.bench.parts.part_json`)."""
        from vinadv.bench.parts import PART_FORMAT, part_json  # noqa: PLC0415 (light)

        return part_json(self.entry) if self.entry.get("format") == PART_FORMAT else entry_json(self.entry)


def run(
    config: BenchConfig,
    executor: Executor = LOCAL,
    *,
    db: str | None = None,
    resume: bool = False,
    progress: bool = False,
    device: str | None = None,
    reuse=None,
    chunks: str | list[int] | None = None,
    parts=(),
) -> BenchResult:
    """The entry of the planner of `config` on its suite (`run_bench`), its chunks computed on `executor`; with `db`
    each chunk stored when done, with `resume` the stored ones read. `device`: where the planner's forward runs.
    `reuse`: an older entry's file (or `vinadv.bench.reuse.ReusedEntry`, as read), whose attack groups that did not
    change are taken (`vinadv.bench.reuse`). `chunks`: only these chunks (a list, or a text such as "0-4,9":
    `vinadv.bench.parts.parse_chunks`), the result a part of the entry (`run_part`); `parts`: part files (or
    `vinadv.bench.parts.Part`, as read) whose chunks are taken. A part holds no submission: InputError naming the
    first of `config`'s submission fields given with `chunks`."""
    from vinadv.errors import InputError  # noqa: PLC0415 (light; beside the planners' import)
    from vinadv.planners.registry import PlannerRef, load_planner  # noqa: PLC0415 (loaded when a job runs)

    if resume and db is None:
        raise InputError("resume: only with db", "resume", "db")
    suite = config.frozen_suite
    if reuse is not None:  # read and checked before the planner loads
        from vinadv.bench.reuse import ReusedEntry  # noqa: PLC0415 (only with an entry to reuse)

        reuse = reuse if isinstance(reuse, ReusedEntry) else ReusedEntry.read(reuse)
    if chunks is not None or parts:  # read and checked before the planner loads
        from vinadv.bench.parts import Part, parse_chunks  # noqa: PLC0415 (only in parts)

        if chunks is not None:
            text = chunks if isinstance(chunks, str) else ",".join(map(str, chunks))
            chunks = parse_chunks(text, -(-suite.n // suite.chunk))
            given = [name for name, value in config.submission.items() if value]
            if given:  # what is shared is given where the entry is made from the parts
                raise InputError(
                    f"{given[0]}: a part holds no submission (chunks writes one); give it with parts, where the "
                    "entry is made",
                    given[0],
                    "chunks",
                    "parts",
                )
        parts = [p if isinstance(p, Part) else Part.read(p, suite) for p in parts]
    # the planner runs under the suite's rule (a planner trained on other maps too: its entry's `other_rules` flag)
    cuts = suite.cuts_corners()
    planner = load_planner(
        config.planner, suite.size, weights=config.weights, corner_cutting=cuts, device=device, moves=suite.movement()
    )
    ref = PlannerRef.of(planner, config.planner, config.weights, corner_cutting=cuts) if executor.remote else None
    common = dict(
        db=db, resume=resume, progress=progress, data=config.data, executor=executor, planner_ref=ref, reuse=reuse
    )
    if chunks is not None:
        return BenchResult(run_part(suite, planner, chunks, parts=parts, **common))
    return BenchResult(run_bench(suite, planner, submission=config.submission, parts=parts, **common))


__all__ = ["BenchConfig", "BenchResult", "run"]
