"""Reading `torch.save` files without PyTorch: the same values as `torch.load(weights_only=True)`, or None."""

import collections
import pickle
import subprocess
import sys
import zipfile

import numpy as np
import pytest
import torch

from vinadv.errors import InputError
from vinadv.planners.torchfile import read_torch_file


def as_numpy(value):
    """`torch.load`'s object with NumPy arrays for tensors (the oracle)."""
    if isinstance(value, torch.Tensor):
        return value.numpy()
    if isinstance(value, dict):
        return {key: as_numpy(v) for key, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(as_numpy(v) for v in value)
    return value


def assert_same(got, want):
    if isinstance(want, np.ndarray):
        assert isinstance(got, np.ndarray) and got.dtype == want.dtype and got.shape == want.shape
        np.testing.assert_array_equal(got, want)
    elif isinstance(want, dict):
        assert isinstance(got, dict) and list(got) == list(want)
        for key in want:
            assert_same(got[key], want[key])
    elif isinstance(want, (list, tuple)):
        assert type(got) is type(want) and len(got) == len(want)
        for g, w in zip(got, want):
            assert_same(g, w)
    else:
        assert got == want and type(got) is type(want)


def saved(tmp_path, obj, **kwargs):
    path = tmp_path / "file.pt"
    torch.save(obj, path, **kwargs)
    return path


def test_reads_what_torch_load_reads(tmp_path):
    base = torch.arange(60, dtype=torch.float32).reshape(3, 4, 5)
    state = collections.OrderedDict(
        [
            ("conv.weight", torch.randn(4, 2, 3, 3)),
            ("scalar", torch.tensor(2.5, dtype=torch.float64)),
            ("half", torch.randn(7).half()),
            ("index", torch.arange(5)),
            ("flags", torch.tensor([True, False])),
            ("view", base[1:, ::2, 1:4]),  # an offset, strided view of a storage shared with the next entry
            ("transposed", base.transpose(0, 2)),
            ("empty", torch.zeros(0, 3)),
        ]
    )
    obj = {"format": "x/1", "config": {"k": 3, "name": "a", "ok": True, "none": None}, "state_dict": state}
    path = saved(tmp_path, obj)
    want = as_numpy(torch.load(path, weights_only=True))
    got = read_torch_file(path)
    assert_same(got, want)
    assert isinstance(got["state_dict"], collections.OrderedDict)


def test_reads_a_module_state_dict_with_its_metadata(tmp_path):
    module = torch.nn.Sequential(torch.nn.Conv2d(2, 3, 3), torch.nn.Linear(4, 2))
    path = saved(tmp_path, module.state_dict())
    assert_same(read_torch_file(path), as_numpy(torch.load(path, weights_only=True)))


@pytest.mark.parametrize(
    "make",
    [
        lambda p: torch.save({"w": torch.randn(3).bfloat16()}, p),  # NumPy has no bfloat16
        lambda p: torch.save({"w": torch.randn(3)}, p, _use_new_zipfile_serialization=False),  # the legacy format
        lambda p: torch.save({"w": torch.nn.Parameter(torch.randn(3))}, p),  # another rebuild function
        lambda p: torch.save({"d": torch.device("cpu")}, p),  # another class
        lambda p: p.write_bytes(b"not a torch file"),
    ],
    ids=["bfloat16", "legacy", "parameter", "device", "garbage"],
)
def test_anything_else_is_left_to_pytorch(tmp_path, make):
    path = tmp_path / "file.pt"
    make(path)
    assert read_torch_file(path) is None
    assert read_torch_file(tmp_path / "missing.pt") is None


def test_a_pickle_never_runs_code(tmp_path):
    class Shell:
        def __reduce__(self):
            return (subprocess.call, (["touch", str(tmp_path / "ran")],))

    path = saved(tmp_path, {"w": torch.randn(2)})
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    (pkl,) = [name for name in members if name.endswith("/data.pkl")]
    members[pkl] = pickle.dumps(Shell(), protocol=2)
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    assert read_torch_file(path) is None
    assert not (tmp_path / "ran").exists()


def test_a_view_outside_its_storage_is_refused(tmp_path):
    path = saved(tmp_path, {"w": torch.arange(6, dtype=torch.float32)})
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    (storage,) = [name for name in members if "/data/" in name and not name.endswith(".pkl")]
    members[storage] = members[storage][:8]  # two floats left of six
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    with pytest.raises(InputError, match="a damaged weights file"):  # never handed to torch.load, which checks less
        read_torch_file(path)


def test_shipped_vin_weights_load_without_pytorch():
    code = (
        "import sys\n"
        "from vinadv.planners.vin.weights import load_vin_weights\n"
        "w = load_vin_weights(None, 28)\n"
        "assert 'torch' not in sys.modules, 'PyTorch loaded'\n"
        "print(w.config.l_h, w.state['h.weight'].dtype)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["150", "float32"]
