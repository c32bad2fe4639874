"""What the near-tie replay measured and checked of PyTorch: in memory per process (`ReplayCache`, one instance
`CACHE`), and on disk per machine (`cache_path()`, keyed by `machine_key()`), so that a later process replays
without loading PyTorch at all. Delete the file to measure again.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import json
import os
import platform
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["CACHE", "CACHE_ENV", "CACHE_FORMAT", "ReplayCache", "cache_path", "machine_key", "torch_threads_now"]

#: environment variable naming the folder of the measured settings ("" keeps nothing on disk)
CACHE_ENV = "VINADV_CACHE_DIR"
CACHE_FORMAT = "vinadv.torch-replay-cache/1"
#: environment variables that can change PyTorch's (MKL's, OpenMP's) float32 results or its thread count
ENVIRONMENT = (
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
    "MKL_CBWR",
    "MKL_ENABLE_INSTRUCTIONS",
    "MKL_DEBUG_CPU_TYPE",
    "MKL_DYNAMIC",
    "OMP_DYNAMIC",
    "ATEN_CPU_CAPABILITY",
)


def cache_path() -> Path | None:
    """The file keeping the measured settings: `$VINADV_CACHE_DIR/torch_replay.json`, else under
    `$XDG_CACHE_HOME/vinadv` or `~/.cache/vinadv`; None when `VINADV_CACHE_DIR` is set empty (nothing kept)."""
    folder = os.environ.get(CACHE_ENV)
    if folder is None:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        folder = os.path.join(base, "vinadv")
    return Path(folder) / "torch_replay.json" if folder else None


@functools.cache
def machine_key() -> str:
    """What PyTorch's float32 results may depend on besides the thread count, hashed: PyTorch's version (which fixes
    the MKL it ships), the CPU's model and instruction sets, the cores this process may use and the BLAS/OpenMP
    environment variables."""
    model, flags = platform.processor(), ""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                name, _, value = line.partition(":")
                if name.strip() == "model name" and not flags:
                    model = value.strip()
                elif name.strip() in ("flags", "Features"):
                    flags = value.strip()
                    break
    except OSError:
        pass
    try:
        torch_version = importlib.metadata.version("torch")
    except importlib.metadata.PackageNotFoundError:
        torch_version = None
    parts = [
        torch_version,
        platform.machine(),
        model,
        flags,
        len(os.sched_getaffinity(0)),
        {name: os.environ.get(name) for name in ENVIRONMENT},
    ]
    return hashlib.sha256(json.dumps(parts, sort_keys=True).encode()).hexdigest()[:24]


def read_cache_file() -> dict:
    """The cache file's contents, `{"format": CACHE_FORMAT, "machines": {machine key: {kind: {key: value}}}}`; an
    empty one where the file is missing, unreadable or of another format."""
    path = cache_path()
    try:
        data = json.loads(path.read_text()) if path is not None else None
    except (OSError, ValueError):
        data = None
    ok = isinstance(data, dict) and data.get("format") == CACHE_FORMAT and isinstance(data.get("machines"), dict)
    return data if ok else {"format": CACHE_FORMAT, "machines": {}}


@dataclass(eq=False)
class ReplayCache:
    """What the replay knows of PyTorch's arithmetic in this process. Settings end with PyTorch's thread count.

    - `conv_modes`: (N, out channels, in channels, bias, threads) -> per-channel fused flags `(out,)` bool;
    - `sum_orders`: (N, l_h, threads) -> (fused, split) of the r layer;
    - `fc_orders`: (l_q, actions, threads) -> (summation tree, fused) of `fc`;
      each None where no replay reproduces PyTorch;
    - `q_verified`, `fc_verified`: setting -> value maps (N, l_h, l_q, threads) or near-tie cells (l_q, actions,
      threads) found equal to PyTorch's; `q_failed`, `fc_failed`: the settings where one differed;
    - `disk`: this machine's entries of the cache file, `{kind: {key: value}}`, read at the first use.
    """

    conv_modes: dict[tuple[int, int, int, bool, int], np.ndarray | None] = field(default_factory=dict)
    sum_orders: dict[tuple[int, int, int], tuple[bool, int] | None] = field(default_factory=dict)
    fc_orders: dict[tuple[int, int, int], tuple[tuple, bool] | None] = field(default_factory=dict)
    q_verified: dict[tuple[int, int, int, int], int] = field(default_factory=dict)
    q_failed: set[tuple[int, int, int, int]] = field(default_factory=set)
    fc_verified: dict[tuple[int, int, int], int] = field(default_factory=dict)
    fc_failed: set[tuple[int, int, int]] = field(default_factory=set)
    disk: dict[str, dict] | None = None

    def entries(self) -> dict[str, dict]:
        """This machine's entries of the cache file, `{kind: {key: value}}` (read at the first call)."""
        if self.disk is None:
            self.disk = read_cache_file()["machines"].get(machine_key(), {})
        return self.disk

    def recall(self, kind: str, key: tuple) -> tuple[bool, object]:
        """`(True, value)` if `kind` was measured for `key` on this machine, else `(False, None)`."""
        entries = self.entries().get(kind, {})
        name = ",".join(map(str, key))
        return name in entries, entries.get(name)

    def remember(self, kind: str, key: tuple, value) -> None:
        """Keep a measurement (JSON value) for this machine, in memory and in the cache file (merged with what other
        processes wrote there; a file that cannot be written costs time later, never correctness)."""
        self.entries().setdefault(kind, {})[",".join(map(str, key))] = value
        path = cache_path()
        if path is None:
            return
        data = read_cache_file()
        mine = data["machines"].setdefault(machine_key(), {})
        for name, entries in self.entries().items():
            mine.setdefault(name, {}).update(entries)
        tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp.write_text(json.dumps(data, sort_keys=True))
            os.replace(tmp, path)
        except OSError:
            pass

    def measured(self, kind: str, key: tuple, measure: Callable[[], object], decode=lambda value: value):
        """The value of `kind` for `key`: kept on disk for this machine, else `measure()` (with PyTorch) and kept."""
        found, value = self.recall(kind, key)
        if not found:
            value = measure()
            self.remember(kind, key, value)
        return None if value is None else decode(value)

    def trusted(self, kind: str, setting: tuple, counts: dict, needed: int) -> bool:
        """Whether a setting's checks are done: `needed` checks passed in this process, or before on this machine."""
        if counts.get(setting, 0) < needed and self.recall(kind, setting)[0]:
            counts[setting] = needed
        return counts.get(setting, 0) >= needed

    def passed(self, kind: str, setting: tuple, counts: dict, needed: int) -> None:
        """One check of a setting passed; with the `needed`-th, the setting is trusted on this machine from now on."""
        counts[setting] = counts.get(setting, 0) + 1
        if counts[setting] == needed:
            self.remember(kind, setting, True)


#: the process-wide cache every function of the replay reads and fills
CACHE = ReplayCache()


def torch_threads_now() -> int:
    """PyTorch's intra-op thread count: `torch.get_num_threads()` once PyTorch is loaded; before that, the count it
    starts with on this machine (read once, kept on disk)."""
    if "torch" in sys.modules:
        return sys.modules["torch"].get_num_threads()

    def first_count() -> int:
        import torch

        return torch.get_num_threads()

    return int(CACHE.measured("default_threads", (), first_count))
