"""Fuzzing every loader: random mutations of valid files (bytes truncated or flipped; arrays dropped, renamed,
retyped, reshaped or given odd values; weights tensors reshaped) either load or raise InputError in one line, never
anything else (the CLI turns InputError into one line and exit status 2). The mutations that make a file
definitely invalid (a file cut short, a required field missing, a field of another shape or of text for numbers,
a weights tensor changed) are refused, every one, and the tests count them so that a loader accepting everything
fails. ~30 examples per loader; well under a minute."""

from __future__ import annotations

import dataclasses
import functools
import io
import sqlite3
import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.fault_files import (
    forge_npy_header,
    read_npz,
    write_classifier,
    write_database,
    write_maps,
    write_pairs,
    write_paths,
    write_weights,
)
from vinadv.attacks.pairs import PairSet
from vinadv.classify import load_model
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.grid.mapset import MapSet
from vinadv.interop import export_maps, read_maps
from vinadv.planners.pathset import PathSet
from vinadv.planners.vin.weights import read_weights
from vinadv.store import Store
from vinadv.testing.classify import synthetic_pairs

# torch warns about the odd pickle protocols of damaged files; the test is about what vinadv raises
pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")

FUZZ = settings(
    max_examples=30,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


def _write_maps(path):
    """The maps file with vinadv.maps/3's optional fields too: a frozen mask and provenance."""
    maps = MapSet.load(write_maps(path))
    frozen = np.zeros(maps.obstacles.shape, dtype=bool)
    frozen[:, -1] = True
    n = len(maps)
    dataclasses.replace(
        maps,
        frozen=frozen,
        source=np.array(["a.map"] * n),
        source_sha256=np.array(["0f" * 32] * n),
        origin=np.zeros((n, 2), np.int64),
    ).save(path)
    return path


def _load_maps(path):
    return MapSet.load(path)


def _load_paths(path):
    return PathSet.load(path)


def _load_pairs(path):
    return PairSet.load(path)


def _load_weights(path):

    model, _ = read_weights(path, size=10)
    with torch.no_grad():  # the loaded model must run: a shape that only fails in conv2d is a loader bug
        model.action_logits(torch.zeros(1, 2, 10, 10))
    return model


@functools.cache
def _pairs():
    return synthetic_pairs(4, size=8, seed=5)  # the size of `write_classifier`'s model


def _load_classifier(path):
    model = load_model(path)
    model.predict(_pairs())  # the loaded model must run: arrays that only disagree in its kernel are a loader bug
    return model


def _load_database(path):
    with Store.open(str(path), create=False) as store:
        for run in store.list_runs():
            store.read_pairs(run["id"])
    return True


WRITERS = {
    "maps": (_write_maps, _load_maps),
    "paths": (write_paths, _load_paths),
    "pairs": (write_pairs, _load_pairs),
    "weights": (write_weights, _load_weights),
    "classifier": (write_classifier, _load_classifier),
    "database": (write_database, _load_database),
}


@pytest.fixture(scope="module")
def valid(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fuzz")
    return {
        kind: write(folder / f"{kind}.{'db' if kind == 'database' else 'npz'}") for kind, (write, _) in WRITERS.items()
    }


#: the kinds written as NumPy .npz archives (the weights are torch.save's zip, the database SQLite)
NPZ = ("maps", "paths", "pairs", "classifier")

#: the fields a loader reads with a default where a file lacks them (files written before the field existed):
#: dropping or renaming one leaves a valid file. Every other field is required.
OPTIONAL = {
    "maps": {"corner_cutting", "seed", "frozen", "source", "source_sha256", "origin"},
    "paths": {"corner_cutting", "model"},
    "pairs": {"corner_cutting", "edit"},
    "classifier": {"record"},
}


def _refused(load, path: Path) -> bool:
    """Whether `load` refused `path`: True after a one-line InputError, False when it loaded; anything else
    propagates (a loader bug)."""
    try:
        load(path)
    except InputError as exc:
        assert str(exc) and "\n" not in str(exc).strip(), repr(exc)
        return True
    return False


def _same_arrays(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(
        a[k].dtype == b[k].dtype and np.array_equal(a[k], b[k], equal_nan=a[k].dtype.kind == "f") for k in a
    )


def _sqlite_page_size(data: bytes) -> int:
    size = int.from_bytes(data[16:18], "big")  # the header's page size; 1 stands for 65536
    return 65536 if size == 1 else size


# ------------------------------------------------------------------------------------------- byte mutations

_bytes_mutation = st.one_of(
    st.tuples(st.just("truncate"), st.floats(0, 1)),
    st.tuples(st.just("flip"), st.lists(st.tuples(st.floats(0, 1), st.integers(1, 255)), min_size=1, max_size=8)),
)


def _mutate_bytes(data: bytes, mutation) -> bytes:
    kind, arg = mutation
    if kind == "truncate":
        return data[: int(arg * len(data))]
    out = bytearray(data)
    for where, xor in arg:
        out[min(len(out) - 1, int(where * len(out)))] ^= xor
    return bytes(out)


@pytest.mark.parametrize("kind", list(WRITERS))
def test_byte_mutations_give_input_errors(kind, valid, tmp_path):
    """Every cut is refused (a zip's directory is at its end; SQLite counts a database's pages by its size, so a
    cut within the last page alone may go unseen); some flips are. A flipped .npz that loads holds the original
    arrays (zip's CRC-32 covers them: the flip fell on a time stamp or the like)."""
    data = valid[kind].read_bytes()
    load = WRITERS[kind][1]
    target = tmp_path / valid[kind].name
    # the shortest cut that must be refused: one byte, or for the database a whole page
    cut = _sqlite_page_size(data) if kind == "database" else 1
    original = read_npz(valid[kind]) if kind in NPZ else None
    seen: list[tuple[str, int, bool]] = []  # (mutation, bytes removed, refused)

    @FUZZ
    @given(mutation=_bytes_mutation)
    def check(mutation):
        mutated = _mutate_bytes(data, mutation)
        target.write_bytes(mutated)
        for extra in tmp_path.glob(target.name + "-*"):  # a mutated database's leftover -wal/-shm
            extra.unlink()
        refused = _refused(load, target)
        if not refused and original is not None:
            assert _same_arrays(read_npz(target), original), mutation  # never a wrong read
        if mutated != data:
            seen.append((mutation[0], len(data) - len(mutated), refused))

    check()
    cuts = [refused for what, removed, refused in seen if what == "truncate" and removed >= cut]
    flips = [refused for what, _, refused in seen if what == "flip"]
    assert cuts and all(cuts), seen
    assert flips and any(flips), seen


# ------------------------------------------------------------------------------------------- array mutations


def _odd_value(draw, arr: np.ndarray):
    if arr.dtype.kind in "iu":
        return draw(st.sampled_from([-1, 0, 1, 2**15 - 1, -(2**15), int(np.iinfo(arr.dtype).max)]))
    if arr.dtype.kind == "f":
        return draw(st.sampled_from([np.nan, np.inf, -1.0, 0.0, 1e30]))
    if arr.dtype.kind == "b":
        return draw(st.booleans())
    return draw(st.sampled_from(["", "x", "goal", "{", "[]", "vinadv.maps/9"]))


@st.composite
def _array_mutation(draw, names: list[str]):
    return (
        draw(st.sampled_from(["drop", "rename", "dtype", "reshape", "value", "empty"])),
        draw(st.sampled_from(names)),
        draw(st.randoms(use_true_random=False)),
    )


def _mutate_arrays(arrays: dict, mutation, draw_value) -> dict:
    op, name, rnd = mutation
    arrays = dict(arrays)
    arr = arrays[name]
    if op == "drop":
        del arrays[name]
    elif op == "rename":
        arrays[name + "_x"] = arrays.pop(name)
    elif op == "dtype":
        target = rnd.choice([np.int8, np.int64, np.float32, np.bool_, np.uint16, "U3"])
        try:
            arrays[name] = arr.astype(target)
        except (ValueError, TypeError):
            arrays[name] = np.zeros(arr.shape, dtype=target)
    elif op == "reshape":
        choice = rnd.randrange(3)
        arrays[name] = (
            arr.reshape(-1)
            if choice == 0
            else arr[None]
            if choice == 1
            else arr[: max(0, len(arr) - 1)]
            if arr.ndim
            else arr.reshape(1)
        )
    elif op == "value" and arr.size:
        arr = arr.copy()
        arr.flat[rnd.randrange(arr.size)] = draw_value(arr)
        arrays[name] = arr
    elif op == "empty":
        arrays[name] = arr[:0] if arr.ndim else np.array([], dtype=arr.dtype)
    return arrays


def _definitely_invalid(kind: str, arrays: dict, mutated: dict, name: str) -> bool:
    """Whether the mutation of field `name` made the file invalid whatever the loader: a required field missing, a
    field of another shape, or text where numbers were (or the other way round). Other dtypes and odd values may
    be valid."""
    if name not in mutated:
        return name not in OPTIONAL[kind]
    before, after = arrays[name], mutated[name]
    return after.shape != before.shape or (after.dtype.kind == "U") != (before.dtype.kind == "U")


@pytest.mark.parametrize("kind", NPZ)
def test_array_mutations_give_input_errors(kind, valid, tmp_path):
    arrays = read_npz(valid[kind])
    load = WRITERS[kind][1]
    target = tmp_path / f"{kind}.npz"
    invalid: list[tuple[tuple, bool]] = []  # (mutation, refused) of the definitely invalid files

    @FUZZ
    @given(data=st.data())
    def check(data):
        mutation = data.draw(_array_mutation(sorted(arrays)))
        mutated = _mutate_arrays(arrays, mutation, lambda arr: _odd_value(data.draw, arr))
        with open(target, "wb") as fh:
            np.savez(fh, **mutated)
        refused = _refused(load, target)
        if _definitely_invalid(kind, arrays, mutated, mutation[1]):
            invalid.append((mutation[:2], refused))

    check()
    assert invalid and all(refused for _, refused in invalid), invalid


class _Pick:
    """A stand-in for `random.Random` in `_mutate_arrays`: picks choice `i` (of its dtypes, of its reshapes)."""

    def __init__(self, i: int):
        self.i = i

    def choice(self, seq):
        return seq[self.i]

    def randrange(self, n: int) -> int:
        return self.i


@pytest.mark.parametrize("kind", NPZ)
def test_every_structural_mutation_of_every_field_is_refused_when_definitely_invalid(kind, valid, tmp_path):
    """Each field dropped, renamed, reshaped (each way), emptied and retyped (each dtype), one at a time: every
    definitely invalid file (`_definitely_invalid`) is refused; the others load or are refused."""
    arrays = read_npz(valid[kind])
    load = WRITERS[kind][1]
    target = tmp_path / f"{kind}.npz"
    accepted = []
    invalid = 0
    for name in sorted(arrays):
        for op, picks in (("drop", 1), ("rename", 1), ("reshape", 3), ("empty", 1), ("dtype", 6)):
            for i in range(picks):
                mutated = _mutate_arrays(arrays, (op, name, _Pick(i)), None)
                with open(target, "wb") as fh:
                    np.savez(fh, **mutated)
                refused = _refused(load, target)
                if _definitely_invalid(kind, arrays, mutated, name):
                    invalid += 1
                    if not refused:
                        accepted.append((op, i, name))
    assert invalid >= len(arrays) and not accepted, accepted


def test_weights_mutations_give_input_errors(valid, tmp_path):
    """Every mutation that changed a tensor, the config or the layout is refused (a shape that stayed the same
    loads)."""
    payload = torch.load(valid["weights"], weights_only=True)
    target = tmp_path / "w.pt"
    seen: list[tuple[str, str, bool]] = []  # (op, key, refused) of the changed files

    @FUZZ
    @given(
        key=st.sampled_from(sorted(payload["state_dict"])),
        op=st.sampled_from(["shape", "drop", "dtype", "nan", "plain", "config"]),
        axis=st.integers(0, 3),
        by=st.integers(-1, 2),
    )
    def check(key, op, axis, by):
        state = dict(payload["state_dict"])
        tensor = state[key]
        data = {**payload, "state_dict": state}
        changed = True
        if op == "shape":
            shape = list(tensor.shape)
            shape[axis % len(shape)] = max(1, shape[axis % len(shape)] + by)
            changed = shape != list(tensor.shape)
            state[key] = torch.zeros(shape)
        elif op == "drop":
            del state[key]
        elif op == "dtype":
            state[key] = tensor.to(torch.int64)
        elif op == "nan":
            state[key] = tensor.clone().fill_(float("nan"))
        elif op == "plain":  # a port-style plain state dict with a reshaped tensor
            shape = list(tensor.shape)
            shape[axis % len(shape)] += abs(by) + 1
            data = {**state, key: torch.zeros(shape)}
        elif op == "config":
            data["config"] = {**payload["config"], "l_i": 3 + by if by >= 0 else 1}
        buf = io.BytesIO()
        torch.save(data, buf)
        target.write_bytes(buf.getvalue())
        refused = _refused(_load_weights, target)
        if changed:
            seen.append((op, key, refused))

    check()
    assert seen and all(refused for _, _, refused in seen), seen


def test_mp_import_header_forgeries_give_input_errors(tmp_path):
    """An MP file (`maps import --format mpd`) with one array's `.npy` header forged (an axis grown, shrunk or
    emptied, another dtype; the data left as it was): the importer loads the split or refuses in one line, and a
    header that claims more bytes than the archive holds for it is refused, every one, before NumPy allocates it."""
    valid = tmp_path / "mp.npz"
    for split in ("train", "valid", "test"):  # one split per file, so a file of every split is made
        export_maps(generate_maps(3, 10, seed=4, n_starts=1, moves="moore"), tmp_path / f"{split}.npz", "mpd", split)
    arrays = {}
    for i, split in enumerate(("train", "valid", "test")):
        part = read_npz(tmp_path / f"{split}.npz")
        arrays.update({f"arr_{4 * i + j}": part[f"arr_{4 * i + j}"] for j in range(4)})
    np.savez(valid, **arrays)
    target = tmp_path / "forged.npz"
    past: list[
        tuple[str, tuple, str, bool]
    ] = []  # the forgeries claiming more than the data: (name, shape, dtype, refused)

    @FUZZ
    @given(
        index=st.integers(0, 11),
        axis=st.integers(0, 4),
        size=st.sampled_from([0, 1, 2, 7, 10**6, 10**12]),
        dtype=st.sampled_from([None, "<f8", "<c16", "|u1", "<i2"]),
    )
    def check(index, axis, size, dtype):
        name = f"arr_{index}"
        shape = list(arrays[name].shape)
        shape[axis % len(shape)] = size
        forge_npy_header(valid, target, name, tuple(shape), dtype)
        split = ("train", "valid", "test")[index // 4]
        refused = _refused(lambda path: read_maps(path, "mpd", split=split), target)
        claimed = int(np.prod(shape, dtype=object)) * np.dtype(dtype or arrays[name].dtype).itemsize
        if claimed > arrays[name].nbytes:
            past.append((name, tuple(shape), dtype, refused))

    check()
    assert past and all(refused for *_, refused in past), past


def test_random_bytes_as_weights_say_what_the_file_is_not(tmp_path):
    path = tmp_path / "noise.pt"
    path.write_bytes(np.random.default_rng(0).bytes(4096))
    with pytest.raises(InputError) as err:
        read_weights(path)
    assert "not a vinadv/PyTorch weights file" in str(err.value) and "weights_only" not in str(err.value)
    zipped = tmp_path / "zip.pt"
    with zipfile.ZipFile(zipped, "w") as z:
        z.writestr("a.txt", "hello")
    with pytest.raises(InputError, match="not a vinadv/PyTorch weights file") as err:
        read_weights(zipped)
    assert "weights_only" not in str(err.value)


def test_plain_state_dict_with_wrong_input_channels_names_key_and_shapes(valid, tmp_path):
    state = dict(torch.load(valid["weights"], weights_only=True)["state_dict"])
    state["h.weight"] = torch.zeros(150, 3, 3, 3)
    path = tmp_path / "port.pt"
    torch.save(state, path)
    with pytest.raises(InputError) as err:
        read_weights(path, size=10)
    message = str(err.value)
    assert "'h.weight'" in message and "(150, 3, 3, 3)" in message and "(150, 2, 3, 3)" in message


@pytest.mark.parametrize(
    ("mangle", "message"),
    [
        ("map_o = '0101'", "map 2: 4 characters, expected 29 for a 5x5 map"),
        ("path_a = 'x,y'", "path 2: not 'row,col' cells joined by ';': 'x,y'"),
        ("map_o = '0101', path_a = 'x,y'", "path 2: not 'row,col' cells joined by ';': 'x,y'"),
    ],
    ids=["map", "path", "both"],
)
def test_database_that_is_a_vinadv_file_with_mangled_rows(valid, tmp_path, mangle, message):
    """Text columns changed behind vinadv's back (a map of the wrong length, a path that is no cells): reading the
    run refuses it every time, in one line naming the column and the row, and never a wrong read; the other rows
    still read right, and a read-only open leaves the file byte-identical."""
    path = tmp_path / "mangled.db"
    path.write_bytes(valid["database"].read_bytes())
    conn = sqlite3.connect(path)
    conn.execute(f"UPDATE map_pairs SET {mangle} WHERE pair_index = 2")
    conn.commit()
    conn.close()
    with Store.open(str(valid["database"]), readonly=True) as store:
        (run,) = store.list_runs()
        intact = store.read_pairs(run["id"], pair_indices=[0, 1, 3, 4, 5])
    assert len(intact) == 5
    before = path.read_bytes()
    with Store.open(str(path), readonly=True) as store:
        with pytest.raises(InputError) as err:
            store.read_pairs(run["id"])
        assert store.read_pairs(run["id"], pair_indices=[0, 1, 3, 4, 5]).equals(intact)
    assert str(err.value) == message
    assert path.read_bytes() == before
    with pytest.raises(InputError) as err:  # the loader every command goes through says the same
        _load_database(path)
    assert str(err.value) == message
