"""The Moving AI suites: real maps (Sturtevant 2012; the multi-agent set, Stern et al. 2019; docs/guide/real-maps.md).

`MovingAISuite` is a data suite (`vinadv.bench.suites.DataSuite`) whose maps are 64x64 windows drawn by the Moving
AI import (`vinadv.interop.formats.movingai`: `vinadv maps import --format movingai FILE --crop 64 --crops K --seed
S`): each file named with its sha256, `draws` windows drawn from it with seed `maps_seed` plus the file's place in
the list (0 for the first) and its first `DataFile.maps` taken, so a quick suite that draws as many as the full one
holds the first maps of each file of the full one. A 256x256 city map gives crops of its streets; a 64x64 MAPF map
has one window, itself, so each draw is a problem on the whole map (a goal in its largest connected region, a start
by the Neural A* loader's distance bands). The maps' rule is the format's: `octile` moves without corner cutting
(`cuts_corners`). A planner trained on maps of another rule runs under this one, and its entry says so (the
`other_rules` flag, `vinadv.bench.flags`).

Released suites:
- `movingai64-v1`: 50 crops of each city map (Berlin_1_256, Boston_0_256, Milan_0_256, Paris_1_256) and 25
  problems on each 64x64 MAPF map (random-64-64-10, room-64-64-8, room-64-64-16): 275 maps, seeds 0..6; the full
  ensemble of `vin28-v1`.
- `movingai64-quick-v1`: the first 10 of each city's crops and of each MAPF map's problems (70 maps); the quick
  ensemble of `vin28-quick-v1`.
"""

from __future__ import annotations

from dataclasses import dataclass

from vinadv.bench.suites import (
    _FULL_ENSEMBLE,
    _QUICK_ENSEMBLE,
    FROZEN,
    DataFile,
    DataSuite,
    register,
)


@dataclass(frozen=True)
class MovingAISuite(DataSuite):
    """A data suite of windows of `crop` x `crop` drawn from Moving AI `.map` files (module doc): `draws[i]`
    windows drawn from `files[i]` (at least its `maps`, the ones taken)."""

    layout: str = "movingai"
    split: str = "all"
    moves: str = "octile"
    crop: int = 64
    draws: tuple[int, ...] = ()

    def read_options(self, file: DataFile) -> dict:
        """The crops of `file`: its draws, seeded `maps_seed` plus its place in `files` (the same seed would draw
        the same window origins in every 256x256 city)."""
        i = self.files.index(file)
        return super().read_options(file) | {"seed": self.maps_seed + i, "crop": self.crop, "crops": self.draws[i]}

    def cuts_corners(self) -> bool:
        return False


#: the files (`../shared/data/movingai/`, docs/data-sources.md) with their sha256, and how many windows each gives
#: the full suite: the four 256x256 city maps, then the three 64x64 maps of the multi-agent set
_FILES = (
    ("Berlin_1_256.map", "9b886cf590f21fe2075d32c1efa54c56a850e93343d20ced6439cfad729bfdda", 50),
    ("Boston_0_256.map", "2905b83edea3da6de464a0565177122e4f956b39f16196f3c9c27dbedc324dcb", 50),
    ("Milan_0_256.map", "1062ea02c7e841a96bae54fa99f31ef898434ceaa3580c3cbe4d494755f3f8cb", 50),
    ("Paris_1_256.map", "99bed3cf0abdeefdbe7435ee2cb669cd02263d3274fcc97524dd21f2f6eb8442", 50),
    ("random-64-64-10.map", "b31c671228f884a113ca11c41b83630dc042e58e07f9b36da74ec508f82a5659", 25),
    ("room-64-64-8.map", "56946a2411a64631f4ab7ca8dd17439e619ad066fc1d2bf2fd19516fc24f28dc", 25),
    ("room-64-64-16.map", "983df5c9bf0c59799daa107feb1b2d3ed81c5d32bf4b23d019f06161d0be6092", 25),
)
_DRAWS = tuple(k for _, _, k in _FILES)
#: maps of each file the quick suite takes
QUICK_PER_FILE = 10

register(
    MovingAISuite(
        name="movingai64-v1",
        description="275 real 64x64 maps: 50 seeded crops of each of four Moving AI city maps (Berlin, Boston, "
        "Milan, Paris) and 25 problems on each of the three 64x64 MAPF maps (random-64-64-10, room-64-64-8, "
        "room-64-64-16), octile moves without corner cutting, one start each (seeds 0..6, one a file); key-points, "
        "saliency, near-path, random adding k = 1..3; exhaustive adding 1; all five removing 1",
        n=sum(_DRAWS),
        size=64,
        maps_seed=0,
        maps_sha256="fc07f9593cf3a3efaab91e0fdd76f8fdf08e556fd70fc13a6175dfffae315564",
        attacks=_FULL_ENSEMBLE,
        chunk=25,
        files=tuple(DataFile(name, sha, k) for name, sha, k in _FILES),
        draws=_DRAWS,
    )
)
register(
    MovingAISuite(
        name="movingai64-quick-v1",
        description="70 of movingai64-v1's maps: the first 10 crops of each city map and the first 10 problems on "
        "each MAPF map; the cheap attacks only: key-points, saliency, near-path, random adding k = 1..3 and "
        "removing 1",
        n=QUICK_PER_FILE * len(_FILES),
        size=64,
        maps_seed=0,
        maps_sha256="732c212883f1eba1e329f16e1f3e73cc764386d047aa78ed61ee07b77795d92d",
        attacks=_QUICK_ENSEMBLE,
        chunk=10,
        files=tuple(DataFile(name, sha, QUICK_PER_FILE) for name, sha, _ in _FILES),
        draws=_DRAWS,
    )
)

FROZEN.update(
    {
        "movingai64-v1": "1a971856708a8fe80773925edb2d7d402ee6f01a2579cb645e45643108785923",
        "movingai64-quick-v1": "14091a91caa83b020f569e3db8da2486c3def398279f1a303a236bed978b84a1",
    }
)
