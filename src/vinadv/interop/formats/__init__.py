"""Maps of other VIN/GPPN code read into a MapSet and written back out, one module per layout.

The layouts (conventions checked against the real files in docs/guide/interop.md, "Data and models from other VIN/GPPN
code"): `kentsommer` (the common PyTorch port, `.npz`), `avivt` (the VIN authors' `.mat`), `gppn` (`.npz`) and `mpd`
(the MP dataset of Neural A*, `.npz`); each module's docstring says what its arrays hold. `FORMATS` maps a layout's
name to its `Format`: what `read_maps` and `export_maps` dispatch on. What the layouts share (samples regrouped into
maps and trajectories, the file's expert paths reconciled with vinadv's, drawn starts) is in
`vinadv.interop.formats.samples`.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import check_moves, require_moves
from vinadv.interop.formats import avivt, drawn, gppn, kentsommer, movingai, mpd, transpath


@dataclass(frozen=True)
class Format:
    """One foreign layout of maps.

    Attributes:
        read: `read(path, split, starts, seed, moves) -> (MapSet, info)`; `split` None is the layout's default,
            `moves` None the file's own movement model.
        write: `write(maps, path, split) -> counts` (a dict: maps and what else was written), `split` checked.
        splits: the splits `read` takes; `write` takes them but `all`.
        moves: the movement models the layout holds (`vinadv.grid.moves`): what `read` may be asked for and what
            `write` takes.
    """

    read: Callable[[str, str | None, int | None, int, str | None], tuple[MapSet, dict]]
    write: Callable[[MapSet, Path, str], dict]
    splits: tuple[str, ...]
    moves: tuple[str, ...] = ("octile",)
    #: the keyword options `read` takes beyond the five above (movingai: `scen`, `bucket`, `crop`, ...)
    options: tuple[str, ...] = ()
    #: whether `read` takes several files at once (a list of paths as its first argument: transpath)
    several: bool = False

    @property
    def export_splits(self) -> tuple[str, ...]:
        """The splits `write` takes: the ones read, but `all`."""
        return tuple(s for s in self.splits if s != "all")


def _octile(read: Callable[[str, str | None, int | None, int], tuple[MapSet, dict]]):
    """`read` of a layout of the VIN's own `octile` data, which has no other movement model (`Format.moves`)."""
    return lambda path, split, starts, seed, moves: read(path, split, starts, seed)


FORMATS: dict[str, Format] = {
    "kentsommer": Format(_octile(kentsommer.read), kentsommer.write, tuple(kentsommer.SPLITS)),
    "avivt": Format(_octile(avivt.read), avivt.write, avivt.SPLITS),
    "gppn": Format(gppn.read, gppn.write, tuple(gppn.SPLITS), ("moore", "news", "octile")),
    "mpd": Format(mpd.read, mpd.write, mpd.SPLITS, ("moore",)),
    "movingai": Format(
        movingai.read,
        movingai.write,
        ("all",),
        ("octile",),
        ("scen", "bucket", "crop", "crops", "min_free", "corner_cutting"),
    ),
    "ascii": Format(
        drawn.read_ascii, drawn.write_refused("ascii"), ("all",), drawn.MOVES, ("pad_to", "corner_cutting")
    ),
    "png": Format(
        drawn.read_png, drawn.write_refused("png"), ("all",), drawn.MOVES, ("start", "goal", "pad_to", "corner_cutting")
    ),
    "transpath": Format(
        transpath.read, drawn.write_refused("transpath"), ("all",), transpath.MOVES, ("pad_to", "corner_cutting"), True
    ),
}


def _format(format: str) -> Format:
    if format not in FORMATS:
        raise InputError(f"format must be one of {', '.join(FORMATS)}, got {format!r}")
    return FORMATS[format]


def read_maps(
    path: str | os.PathLike | Sequence[str | os.PathLike],
    format: str,
    split: str | None = None,
    starts: int | None = None,
    seed: int = 0,
    moves: str | None = None,
    **options,
) -> tuple[MapSet, dict]:
    """Read maps in another codebase's layout: `(MapSet, info)`; `info` says what was found and done.

    Args:
        path: the file; several files (a list) for a layout that reads them at once (`Format.several`: transpath).
        format: 'kentsommer', 'avivt', 'gppn', 'mpd', 'movingai', 'ascii', 'png' or 'transpath' (`FORMATS`).
        split: kentsommer train|test|all (default test); gppn train|valid|test|all (default test); avivt
            train|test, the layout (default: the one the file has).
        starts: starts per map where the file has none (gppn, avivt's batched-only layout; default 7); files
            with trajectories take theirs and refuse `starts`.
        seed: seed of the drawn starts.
        moves: the movement model of the maps read (`vinadv.grid.moves`); None: the file's own (gppn: `moore` for
            8 actions, `news` for 4; mpd: `moore`; kentsommer and avivt: `octile`). A model the layout cannot hold
            is refused.
        options: what a layout takes beyond these (`Format.options`; None is not given): movingai's `scen`,
            `bucket`, `crop`, `crops`, `min_free` and `corner_cutting` (`vinadv.interop.formats.movingai`); ascii's
            and png's `pad_to` and `corner_cutting`, png's `start` and `goal` (`vinadv.interop.formats.drawn`);
            transpath's `pad_to` and `corner_cutting` (`vinadv.interop.formats.transpath`).

    Raises InputError naming the file and array for a missing array, a wrong shape, other polarity, a goal value
    or label out of range, or a path that is not a legal move sequence to the goal.
    """
    layout = _format(format)
    if split is not None and split not in layout.splits:
        raise InputError(f"split must be one of {', '.join(layout.splits)} for format {format}, got {split!r}")
    if starts is not None and starts < 1:
        raise InputError(f"starts must be >= 1, got {starts}")
    if moves is not None and check_moves(moves) not in layout.moves:
        raise InputError(f"moves {moves!r}: format {format} holds {' or '.join(layout.moves)} maps", "moves")
    given = {k: v for k, v in options.items() if v is not None}
    for name in given:
        if name not in layout.options:
            raise InputError(f"{name} is not an option of format {format}", name)
    if isinstance(path, (str, os.PathLike)):
        path = str(path)
    else:
        paths = [str(p) for p in path]
        if not paths:
            raise InputError(f"no file given to read (format {format})")
        if len(paths) > 1 and not layout.several:
            raise InputError(f"format {format} reads one file, got {len(paths)}: {paths[0]}, {paths[1]}, ...")
        path = paths if layout.several else paths[0]
    maps, info = layout.read(path, split, starts, seed, moves, **given)
    return maps, {"format": format, "file": path, "moves": maps.moves, **info}


def import_maps(path: str | os.PathLike, format: str, *args, **kwargs) -> MapSet:
    """`read_maps` (the same arguments) without the info dict."""
    return read_maps(path, format, *args, **kwargs)[0]


def export_maps(maps: MapSet, path: str | os.PathLike, format: str, split: str | None = None) -> dict:
    """Write `maps` in another codebase's layout; returns a summary dict.

    kentsommer: the samples (every step of every real start's expert path) go to `split` (train|test, default
    test), the other split is written empty; goal prior 10 at the goal, 0 elsewhere. avivt: `split` test (default)
    writes the test layout (one row per real start), train the per-sample training arrays (no batched arrays).
    gppn: the mazes go to `split` (train|valid|test, default test), the others are empty; the policies are
    GPPN's (every move cost 1: `news` maps get 4 actions, `moore` and `octile` maps 8). mpd: the maps go to `split`,
    the others are empty, with their goals, policies and distances (`moore` maps only). movingai (no splits): one
    `.map` per distinct grid and a `.scen` of every real start (octile maps without corner cutting only). A layout is
    written from the movement models it holds (`Format.moves`; InputError otherwise).
    """
    layout = _format(format)
    require_moves(maps.moves, layout.moves, f"export to {format}")
    if not layout.export_splits:  # one grid a file, no splits (movingai)
        if split is not None:
            raise InputError(f"format {format} has no splits, got split {split!r}")
        split = "all"
    elif (split := split or "test") not in layout.export_splits:
        allowed = ", ".join(layout.export_splits)
        raise InputError(f"split must be one of {allowed} to export format {format}, got {split!r}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return {"format": format, "out": str(path), "split": split, **layout.write(maps, path, split)}


__all__ = ["FORMATS", "Format", "export_maps", "import_maps", "read_maps"]
