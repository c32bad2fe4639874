"""Benchmark suites: frozen specifications under a version name, in a registry (`register`, `get_suite`).

A suite says exactly what is run: the maps (our generator, its seed, the number of maps, one start each, and the
sha256 of the maps it makes, checked before a run so a changed generator is refused, not silently compared), the
attack ensemble (groups of strategies, each with its edit, add or remove, and its largest number of edited cells k),
the objective the ranking strategies keep, the randomised strategies' seed, the budget and radius, the harm
tolerances, the flags' thresholds, and the chunk size (maps per resumable unit). Its checksum is the sha256 of its
canonical JSON (`Suite.checksum`); a released suite never changes (`FROZEN` holds every released checksum and a test
holds the registry to it): a change is a new version under a new name.

A `DataSuite` reads its maps from public files instead (`--data DIR`): the spec names each file with its sha256 and
the maps it takes, the layout and split read, the seed of the start draw and the movement model.

Released suites:
- `vin28-v1`: the generator's first 1,000 maps of seed 1000 (the held-out maps of the evaluation tables), one start
  each; key-points, saliency, near-path and random adding 1..3 cells greedily, exhaustive adding one, and all five
  removing one.
- `vin28-quick-v1`: the first 100 of those maps; the cheap attacks only: key-points, saliency, near-path and random
  adding 1..3 cells, and the same four removing one (no exhaustive). For trying and for tests.
- `mpd32-v1`: the test splits of the MP dataset's six families (`docs/guide/mpd.md`: 600 32x32 `moore` maps, corner
  cutting), one start per map drawn by the MP import's rule (the Neural A* loader's) with seed 0; the ensemble of
  `vin28-v1`.
- `mpd32-quick-v1`: 100 of those maps (the first 17 of the first four families in name order, the first 16 of the
  last two); the ensemble of `vin28-quick-v1`.
- `vin28-v2`, `vin28-quick-v2`, `mpd32-v2`, `mpd32-quick-v2`: the maps and ensembles of their `-v1`, of definitions 2
  (`Suite.definitions`): the worst case at k over every attack of at most k edits on a fixed denominator, entries
  `vinadv.bench_entry/2` with per-map outcomes; in the full ones the cheap strategies' steps 2..3 also start from
  exhaustive's one-cell optimum (`AttackGroup.start`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from dataclasses import asdict, dataclass

import numpy as np

from vinadv.errors import InputError

#: the format of a suite's spec (part of what its checksum covers)
SUITE_FORMAT = "vinadv.bench_suite/1"
#: the format of a result entry file of a suite of definitions 1 (`vinadv.bench.scoring`), and of definitions 2
#: (per-map outcomes, budgets of at most k edits: `vinadv.bench.outcomes`)
ENTRY_FORMAT = "vinadv.bench_entry/1"
ENTRY_FORMAT_2 = "vinadv.bench_entry/2"
#: the revision of every strategy of a chunk or an entry made before revisions were recorded (the first one)
UNRECORDED_REVISION = 1
#: every entry format this vinadv reads
ENTRY_FORMATS = (ENTRY_FORMAT, ENTRY_FORMAT_2)


@dataclass(frozen=True)
class AttackGroup:
    """Strategies run together under one edit, each making one pair per map with 1..`max_obstacles` cells edited
    greedily (`vinadv.robustness.robustness`).

    `start`: None, or a strategy of an earlier group of the suite with the same edit and one cell (`exhaustive`):
    each strategy's greedy chain then starts from the one-cell pair that strategy kept on each map (the exhaustive
    one-cell optimum) and makes the pairs of k = 2..`max_obstacles` (`first_k` 2), named `edit:start+strategy`."""

    strategies: tuple[str, ...]
    edit: str
    max_obstacles: int
    start: str | None = None

    def keys(self) -> list[str]:
        """The attacks' names in entries: `edit:strategy` (say `add:saliency`, `remove:random`), and for a group
        started from another strategy's cell `edit:start+strategy` (`add:exhaustive+saliency`)."""
        prefix = "" if self.start is None else f"{self.start}+"
        return [f"{self.edit}:{prefix}{s}" for s in self.strategies]

    @property
    def ks(self) -> range:
        """The numbers of edited cells k of the group's pairs, `first_k..max_obstacles`."""
        return range(self.first_k, self.max_obstacles + 1)

    @property
    def first_k(self) -> int:
        """The fewest cells the group's pairs edit: 1, or 2 for a group started from a one-cell pair."""
        return 1 if self.start is None else 2

    def spec(self) -> dict:
        """The group as JSON types; `start` only where set (the released suites' groups have none, and their
        checksums were taken before the field existed)."""
        out = asdict(self) | {"strategies": list(self.strategies)}
        if self.start is None:
            del out["start"]
        return out


@dataclass(frozen=True)
class Suite:
    """A frozen benchmark specification (see the module doc)."""

    name: str
    description: str
    n: int
    size: int
    maps_seed: int
    maps_sha256: str
    attacks: tuple[AttackGroup, ...]
    objective: str = "harm"
    seed: int = 1000
    budget: int = 8
    radius: int = 2
    harm_tolerance: float = 1e-6
    harm_rtol: float = 0.0
    chunk: int = 50
    #: the flags' thresholds (`vinadv.bench.flags`)
    masking_ratio: float = 3.0
    masking_min_rate: float = 0.10
    weak_clean_success: float = 0.5
    #: the benchmark's definitions: 1, the worst case at k over the attacks that reach k, entries
    #: `vinadv.bench_entry/1`; 2, the worst case at k over every attack of at most k edits on a fixed denominator (a
    #: k curve that cannot fall), entries `vinadv.bench_entry/2` holding the per-map outcomes (`vinadv.bench.outcomes`)
    definitions: int = 1

    def spec(self) -> dict:
        """The canonical specification: every field, as JSON types; `definitions` only where it is not 1 (the
        released suites of definitions 1 had their checksums taken before the field existed)."""
        out = asdict(self)
        out["attacks"] = [g.spec() for g in self.attacks]
        if self.definitions == 1:
            del out["definitions"]
        return {"format": SUITE_FORMAT, **out}

    @property
    def entry_format(self) -> str:
        """The format of the suite's entries: `ENTRY_FORMAT` (definitions 1) or `ENTRY_FORMAT_2`."""
        return ENTRY_FORMAT if self.definitions == 1 else ENTRY_FORMAT_2

    @property
    def checksum(self) -> str:
        """sha256 of the canonical JSON of `spec()`: the suite's identity."""
        text = json.dumps(self.spec(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    def attack_keys(self) -> list[str]:
        return [k for g in self.attacks for k in g.keys()]

    def start_keys(self) -> list[str]:
        """The attacks whose one-cell cells a later group's chain starts from (`AttackGroup.start`: `edit:start`,
        say `add:exhaustive`), in suite order, each once; [] for a suite without chains."""
        keys = [f"{g.edit}:{g.start}" for g in self.attacks if g.start is not None]
        return list(dict.fromkeys(keys))

    def movement(self) -> str:
        """The movement model of the suite's maps (`vinadv.grid.moves`): the generator's `octile`."""
        return "octile"

    def cuts_corners(self) -> bool:
        """Whether the suite's maps let a diagonal move pass between two obstacles: the generator's and the MP
        layout's do."""
        return True


@dataclass(frozen=True)
class DataFile:
    """A public file a data suite reads from `--data DIR`: its name there, its sha256 (checked before it is read),
    and how many of its split's maps the suite takes (the first, in the file's order, after the import)."""

    name: str
    sha256: str
    maps: int


@dataclass(frozen=True)
class DataSuite(Suite):
    """A suite whose maps are read from public files (`files`, in `--data DIR`) rather than generated: each file's
    `split` imported by vinadv's reader of the `layout` (`vinadv.interop.formats`) with one start per map drawn with
    seed `maps_seed` by that reader's start rule, its first `DataFile.maps` maps taken, the files' maps joined in
    order (`maps_sha256` covers the join). `moves`: their movement model."""

    layout: str = "mpd"
    split: str = "test"
    moves: str = "moore"
    files: tuple[DataFile, ...] = ()

    def movement(self) -> str:
        return self.moves

    def read_options(self, file: DataFile) -> dict:
        """The reader's arguments (`vinadv.interop.formats.read_maps`) for `file` beyond its path and the layout:
        the split, one start per map and the seed (`vinadv.bench.movingai_suites` adds its crops)."""
        return {"split": self.split, "starts": 1, "seed": self.maps_seed}


def maps_sha256(obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray) -> str:
    """sha256 of a suite's maps: the obstacles (bool bytes), then the starts and goals (int64 bytes), `(n, 2)` each."""
    digest = hashlib.sha256()
    digest.update(np.ascontiguousarray(obstacles, dtype=bool).tobytes())
    for cells in (starts, goals):
        digest.update(np.ascontiguousarray(cells, dtype=np.int64).tobytes())
    return digest.hexdigest()


SUITES: dict[str, Suite] = {}


def register(suite: Suite) -> Suite:
    """Register `suite` under its name; refuses a name already registered, and a group started from a strategy that
    no earlier group of one cell and the same edit runs (`AttackGroup.start`)."""
    if suite.name in SUITES:
        raise InputError(f"suite {suite.name!r}: a suite of that name is already registered", "suite")
    for i, group in enumerate(suite.attacks):
        before = [g for g in suite.attacks[:i] if g.start is None and g.edit == group.edit and g.max_obstacles == 1]
        if group.start is not None and not any(group.start in g.strategies for g in before):
            raise InputError(
                f"suite {suite.name!r}: group {i} starts from {group.start!r}, which no earlier group of one "
                f"{group.edit}ed cell runs",
                "suite",
            )
    SUITES[suite.name] = suite
    return suite


def get_suite(name: str) -> Suite:
    """The registered suite `name`; InputError (one line, naming the known suites) for an unknown one."""
    if name not in SUITES:
        raise InputError(f"unknown suite {name!r}; the suites are {', '.join(sorted(SUITES))}", "suite")
    return SUITES[name]


_CHEAP = ("key-points", "saliency", "near-path", "random")
#: the ensembles of the full suites and of the quick ones (the same on 28x28 and on MP maps)
_FULL_ENSEMBLE = (
    AttackGroup(_CHEAP, "add", 3),
    AttackGroup(("exhaustive",), "add", 1),
    AttackGroup((*_CHEAP, "exhaustive"), "remove", 1),
)
_QUICK_ENSEMBLE = (AttackGroup(_CHEAP, "add", 3), AttackGroup(_CHEAP, "remove", 1))
#: the full ensemble of definitions 2: the cheap strategies' chains also start from the exhaustive one-cell optimum
_FULL_ENSEMBLE_2 = (
    AttackGroup(_CHEAP, "add", 3),
    AttackGroup(("exhaustive",), "add", 1),
    AttackGroup(_CHEAP, "add", 3, start="exhaustive"),
    AttackGroup((*_CHEAP, "exhaustive"), "remove", 1),
)

register(
    Suite(
        name="vin28-v1",
        description="1,000 held-out 28x28 maps (seed 1000); key-points, saliency, near-path, random adding k = 1..3; "
        "exhaustive adding 1; all five removing 1",
        n=1000,
        size=28,
        maps_seed=1000,
        maps_sha256="631227302404d67d5e959361bf5ae8e5894f0e6a0e0630edfbb238dd821c4e1f",
        attacks=_FULL_ENSEMBLE,
        chunk=50,
    )
)
register(
    Suite(
        name="vin28-quick-v1",
        description="the first 100 of vin28-v1's maps; the cheap attacks only: key-points, saliency, near-path, "
        "random adding k = 1..3 and removing 1",
        n=100,
        size=28,
        maps_seed=1000,
        maps_sha256="3692472c7376f8107fc948abf8eeeaffa0198bfcccf1e1ba8ebdda322ae19a80",
        attacks=_QUICK_ENSEMBLE,
        chunk=25,
    )
)

#: the six families of the MP dataset shipped by planning-datasets (commit a982a04, `data/mpd/`), in name order, with
#: the sha256 of each file (`docs/guide/mpd.md`); each test split holds 100 maps
_MPD_FILES = (
    ("alternating_gaps_032_moore_c8.npz", "3f105d69d68a35738084e658911c877ae09d6ce55c2ea63fa070517cd47ae35e"),
    ("forest_032_moore_c8.npz", "6ec48417fe4d4845e4b73df4c1be0fb2c9cfaedbb456e2c54ae6f49c404361fc"),
    ("mazes_032_moore_c8.npz", "8153402e23dc20098d4f4135de34b5c88316b36e56f5d0c8d59410307499b426"),
    ("multiple_bugtraps_032_moore_c8.npz", "a68a2e2dc65a639b12bb1458ca256972d89859990c65b60d6fd733278e01f32c"),
    ("shifting_gaps_032_moore_c8.npz", "957512936811284f63d2bd9f2d5d533e517b87af9a4f30d8cf307b98af7302e1"),
    ("single_bugtrap_032_moore_c8.npz", "addc67d04432b60f360c275fea43f1b80b77bdb6f5590dbacaf4af532ea020a3"),
)
register(
    DataSuite(
        name="mpd32-v1",
        description="the test splits of the MP dataset's six families (600 32x32 moore maps), one start each drawn "
        "by the Neural A* rule (seed 0); key-points, saliency, near-path, random adding k = 1..3; exhaustive adding "
        "1; all five removing 1",
        n=600,
        size=32,
        maps_seed=0,
        maps_sha256="e99bb4ada1494c2163c8bf54347954f20c77adf392aa1fc46dff65bd951de4d8",
        attacks=_FULL_ENSEMBLE,
        chunk=50,
        files=tuple(DataFile(name, sha, 100) for name, sha in _MPD_FILES),
    )
)
register(
    DataSuite(
        name="mpd32-quick-v1",
        description="100 of mpd32-v1's maps: the first 17 of the test split of alternating_gaps, forest, mazes and "
        "multiple_bugtraps, the first 16 of shifting_gaps and single_bugtrap; the cheap attacks only: key-points, "
        "saliency, near-path, random adding k = 1..3 and removing 1",
        n=100,
        size=32,
        maps_seed=0,
        maps_sha256="b72f05ac1d9b17f5953e40fe1489142e42cbd1c50730201dbdf8540255aaaf60",
        attacks=_QUICK_ENSEMBLE,
        chunk=25,
        files=tuple(DataFile(name, sha, 17 if i < 4 else 16) for i, (name, sha) in enumerate(_MPD_FILES)),
    )
)

#: the suites of definitions 2 (`Suite.definitions`): the maps of their v1, budgets of at most k edits; the full
#: ones' cheap chains also start from the exhaustive one-cell optimum
_V2 = "; the worst case at k over every attack of at most k edits (definitions 2)"


def _register_v2(v1: str, full: bool) -> Suite:
    """The definitions-2 suite of the registered suite `v1` (named `...-v1`): its maps; a `full` one's attacks are
    `_FULL_ENSEMBLE_2`, a quick one keeps its own."""
    suite = SUITES[v1]
    chains = "; key-points, saliency, near-path, random also adding k = 2..3 from exhaustive's one-cell optimum"
    return register(
        dataclasses.replace(
            suite,
            name=v1.removesuffix("-v1") + "-v2",
            description=suite.description + (chains if full else "") + _V2,
            attacks=_FULL_ENSEMBLE_2 if full else suite.attacks,
            definitions=2,
        )
    )


_register_v2("vin28-v1", full=True)
_register_v2("vin28-quick-v1", full=False)
_register_v2("mpd32-v1", full=True)
_register_v2("mpd32-quick-v1", full=False)

#: the checksum of every released suite: a released suite never changes (a test holds the registry to these)
FROZEN = {
    "vin28-v1": "1dad52e25d05f3eca3fab2960c02af1cc15d81736c4e50acf7d569dfdbb92203",
    "vin28-quick-v1": "5d96a8431b05e56aac524464fe37b3794ba7763ca17233523073ad69b78d6157",
    "mpd32-v1": "7f077bd76099849020090308ff5ea0913f609d74e5e6d7643466646c184d92a4",
    "mpd32-quick-v1": "76f5d309d15f7d68838e18cd0c405dd6b4eefe391b4a2ddc02e9f3a4bc59a400",
    "vin28-v2": "e9e3f6e3aa13f726f9749fb94e8f4d97c846e4f29072e8a3071bfb59fecc01ce",
    "vin28-quick-v2": "a9453e8ed147a2cceddd35543a835645304284e8bafe7028c88c1372e26102a0",
    "mpd32-v2": "b3063f6815a07bd1c3519194639d686837e01c41ceb96fdb7b4d14dcc935d395",
    "mpd32-quick-v2": "39389798b94a46f65fdf2fbf15d9874c930ea060756f42b4f5ab59126d662194",
}

# the Moving AI suites (real maps: crops of city streets, problems on the MAPF maps) register themselves and their
# checksums; imported last, as it builds on the classes above
from vinadv.bench import movingai_suites  # noqa: E402, F401
