"""Command lines for the tests of the `vinadv` commands, and the files the end-to-end tests make through them (maps
written by `vinadv maps generate`, then attacked into a pairs file by `vinadv attack`)."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

from vinadv.cli import main
from vinadv.grid import generate_maps


def generated_maps_file(folder: Path, n: int, size: int, *, seed: int, n_starts: int = 1) -> str:
    """Write the generator's `n` maps of `size` (`seed`, `n_starts` starts each) to `folder/maps.npz`; returns its
    path as a string, a command-line argument."""
    path = folder / "maps.npz"
    generate_maps(n, size, seed=seed, n_starts=n_starts).save(path)
    return str(path)


def generate_and_attack(
    folder: Path, weights: str, *, n: int, size: int, strategy: str, options: tuple[str, ...] = ("--quiet",)
) -> tuple[Path, Path]:
    """Write `n` maps of `size` with one start each to `folder/maps.npz` and attack them with `strategy` and the
    planner `weights` into `folder/pairs.npz` (more `options` for `vinadv attack`); both commands must exit 0. The
    maps command's summary is left out of standard output, the attack's prints as `options` say (`--quiet` still
    prints it). Returns the paths of the maps file and of the pairs file."""
    maps, pairs = folder / "maps.npz", folder / "pairs.npz"
    generate = ["maps", "generate", "--n", str(n), "--size", str(size), "--starts", "1", "--out", str(maps), "--quiet"]
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(generate) == 0
    attack = ["attack", "--maps", str(maps), "--strategy", strategy, "--out", str(pairs), "--weights", weights]
    assert main([*attack, *options]) == 0
    return maps, pairs


def command_line(*words: str, **options: object) -> list[str]:
    """The command line `words` followed by `--name value` for each of `options`, in their order; an underscore in a
    name is a dash on the command line (`shard_size=20` is `--shard-size 20`)."""
    line = list(words)
    for name, value in options.items():
        line += [f"--{name.replace('_', '-')}", str(value)]
    return line
