"""The Gated Path Planning Network (Lee et al. 2018, "Gated Path Planning Networks", ICML), 2-D, 8 actions.

The published model replaces the VIN's value iteration by a convolutional LSTM whose input is a convolution of its
own hidden state:

    X   = [free cells (1/0), goal map (1 at the goal)]          (B, 2, N, N)
    hid = conv3x3(X)                                              (B, l_h, N, N)   `hid`
    h_0 = conv3x3(hid), c_0 = conv3x3(hid)                                        `h0`, `c0`
    for t = 1 .. k - 1:
        x_t      = conv_fxf(h_{t-1})  (l_h -> 1 channel, bias)                     `conv`
        h_t, c_t = LSTMCell(x_t, (h_{t-1}, c_{t-1}))  at every cell independently  `lstm`
    logits = conv1x1(h_{k-1})  (l_h -> 8, no bias)                                 `policy`

State-dict keys and shapes are those of the authors' public code (`hid, h0, c0, conv, lstm, policy`), so its 2-D
checkpoints of the same width, kernel and action count load; the input channel 0 is 1 on free cells, as there.

The recurrence is computed without the per-step layout changes of the straightforward code (which runs
`nn.LSTMCell` on `(B * N * N, l_h)` rows and transposes the state back to maps for the convolution at every step):
the state stays in `(B, l_h, N, N)` maps, and the LSTM cell at every cell is one 1x1 convolution of `[h, x]` giving
the gates, ordered so that every elementwise step runs on long contiguous blocks (slices of a `(rows, 4 l_h)` gate
matrix made sigmoid and tanh several times slower). It is the same function: a test holds it to a plain
implementation of the equations above.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import torch
import torch.nn.functional as F
from torch import nn

from vinadv.errors import InputError
from vinadv.outfile import save_torch
from vinadv.planners.weights import MAX_ITERATIONS, as_loaded, torch_load, weights_file

GPPN_FORMAT = "vinadv.gppn/1"
WEIGHTS_DIR = Path(__file__).resolve().parents[2] / "weights"


#: the widest hidden layer (l_h, and the VIN's l_q) a planner may be built with: a GPPN's weights grow with its
#: square (2048: ~0.1 billion parameters, 0.4 GB), and a wider one asked for by a typo or a hostile file would
#: take every byte of memory before any error
MAX_WIDTH = 2048
#: the largest recurrent kernel (f) of a GPPN: far past any map it would plan (its weights grow with f * f * l_h)
MAX_KERNEL = 63


@dataclass(frozen=True)
class GPPNConfig:
    """k iterations (k - 1 LSTM steps, as the published code), l_h hidden channels, f the kernel of `conv`."""

    k: int = 20
    l_h: int = 32
    f: int = 3
    n_actions: int = 8

    def to_dict(self) -> dict:
        return asdict(self)

    def validate(self) -> None:
        if self.k < 1 or self.l_h < 1 or self.n_actions < 1:
            raise InputError(f"GPPN k, l_h and n_actions must be >= 1, got {self.to_dict()}")
        if self.f < 1 or self.f % 2 == 0:
            raise InputError(f"GPPN kernel f must be odd and >= 1, got {self.f}")
        if self.k > MAX_ITERATIONS:
            raise InputError(f"GPPN k must be at most {MAX_ITERATIONS}, got {self.k}", "k")
        if self.l_h > MAX_WIDTH:
            raise InputError(f"GPPN l_h must be at most {MAX_WIDTH}, got {self.l_h}", "l_h")
        if self.f > MAX_KERNEL:
            raise InputError(f"GPPN kernel f must be at most {MAX_KERNEL}, got {self.f}")


class GPPN(nn.Module):
    """`forward(obstacles (B, N, N) float 0/1, goals (B, 2) int64) -> (B, n_actions, N, N)` logits."""

    def __init__(self, config: GPPNConfig = GPPNConfig()):
        super().__init__()
        config.validate()
        self.config = config
        l_h, f = config.l_h, config.f
        self.hid = nn.Conv2d(2, l_h, 3, padding=1, bias=True)
        self.h0 = nn.Conv2d(l_h, l_h, 3, padding=1, bias=True)
        self.c0 = nn.Conv2d(l_h, l_h, 3, padding=1, bias=True)
        self.conv = nn.Conv2d(l_h, 1, f, padding=f // 2, bias=True)
        self.lstm = nn.LSTMCell(1, l_h)
        self.policy = nn.Conv2d(l_h, config.n_actions, 1, bias=False)

    def forward(self, obstacles: torch.Tensor, goals: torch.Tensor) -> torch.Tensor:
        l_h, f = self.config.l_h, self.config.f
        hid = self.hid(input_maps(obstacles, goals))
        h, c = self.h0(hid), self.c0(hid)  # (B, l_h, N, N)
        # The LSTM cell at every cell is a 1x1 convolution of [h, x] giving the four gates, reordered (i, f, o, g)
        # from PyTorch's (i, f, g, o) so the three sigmoid gates are one block of channels.
        order = torch.cat([torch.arange(0, 2 * l_h), torch.arange(3 * l_h, 4 * l_h), torch.arange(2 * l_h, 3 * l_h)])
        w_gates = torch.cat([self.lstm.weight_hh, self.lstm.weight_ih], dim=1)[order][:, :, None, None]
        b_gates = (self.lstm.bias_ih + self.lstm.bias_hh)[order]
        for _ in range(self.config.k - 1):
            x = F.conv2d(h, self.conv.weight, self.conv.bias, padding=f // 2)  # (B, 1, N, N)
            gates = F.conv2d(torch.cat([h, x], dim=1), w_gates, b_gates)
            s = torch.sigmoid(gates[:, : 3 * l_h])
            c = s[:, l_h : 2 * l_h] * c + s[:, :l_h] * torch.tanh(gates[:, 3 * l_h :])
            h = s[:, 2 * l_h :] * torch.tanh(c)
        return self.policy(h)


def widen_gppn(model: GPPN, l_h: int, noise: float = 1e-3, seed: int = 0) -> GPPN:
    """A GPPN of width `l_h` computing the same function as `model` (Net2WiderNet, Chen et al. 2016).

    Each new channel copies an old one (the first `model.config.l_h` keep their place, the others copy old channels
    drawn at random, each at most once while there are fewer new than old), in every layer at once: `hid`, `h0`,
    `c0` and the LSTM's four gates. Whatever reads a copied channel (`h0`, `c0`, `conv`, the LSTM's recurrent
    weights, `policy`) reads each copy with the old weight divided by the number of copies, so every hidden state
    of the wide model is the old one with its channels repeated, and the logits are the same.

    Copies would stay identical under training, so `noise` > 0 adds Gaussian noise of `noise` times each weight
    tensor's standard deviation to the incoming weights of the added channels only: the logits then move a little
    (measured in the tests) and training can tell the copies apart. Returns a new model in eval mode.
    """
    old = model.config.l_h
    GPPNConfig(**{**model.config.to_dict(), "l_h": l_h}).validate()  # before anything of width l_h is made
    if l_h < old:
        raise InputError(f"l_h must be at least the model's width {old} to widen it, got {l_h}", "l_h")
    if not noise >= 0:
        raise InputError(f"noise must be >= 0, got {noise}", "noise")
    rng = torch.Generator().manual_seed(seed)
    extra = l_h - old
    if extra <= old:
        picks = torch.randperm(old, generator=rng)[:extra]
    else:
        picks = torch.randint(old, (extra,), generator=rng)
    source = torch.cat([torch.arange(old), picks])  # new channel -> the old channel it copies
    copies = torch.bincount(source, minlength=old).to(torch.float32)[source]  # (l_h,) copies of each one's source

    def rows(w: torch.Tensor, blocks: int = 1) -> torch.Tensor:  # output channels (in `blocks` gate blocks)
        w = w.reshape(blocks, old, *w.shape[1:])[:, source]
        added = w[:, old:]
        if noise and added.numel():
            scale = noise * float(w.std()) if w.numel() > 1 else noise
            w[:, old:] = added + scale * torch.randn(added.shape, generator=rng)
        return w.reshape(blocks * l_h, *w.shape[2:])

    def cols(w: torch.Tensor) -> torch.Tensor:  # input channels: split the old weight over the copies
        shape = (1, l_h) + (1,) * (w.dim() - 2)
        return w[:, source] / copies.reshape(shape)

    sd = {k: v.detach().clone() for k, v in model.state_dict().items()}
    new = {
        "hid.weight": rows(sd["hid.weight"]),
        "hid.bias": rows(sd["hid.bias"]),
        "h0.weight": rows(cols(sd["h0.weight"])),
        "h0.bias": rows(sd["h0.bias"]),
        "c0.weight": rows(cols(sd["c0.weight"])),
        "c0.bias": rows(sd["c0.bias"]),
        "conv.weight": cols(sd["conv.weight"]),
        "conv.bias": sd["conv.bias"],
        "lstm.weight_ih": rows(sd["lstm.weight_ih"], 4),
        "lstm.weight_hh": rows(cols(sd["lstm.weight_hh"]), 4),
        "lstm.bias_ih": rows(sd["lstm.bias_ih"], 4),
        "lstm.bias_hh": rows(sd["lstm.bias_hh"], 4),
        "policy.weight": cols(sd["policy.weight"]),
    }
    wide = GPPN(GPPNConfig(**{**model.config.to_dict(), "l_h": l_h}))
    wide.load_state_dict(new)
    return wide.eval()


def input_maps(obstacles: torch.Tensor, goals: torch.Tensor) -> torch.Tensor:
    """`(B, 2, N, N)`: free cells (1 - obstacles) and the one-hot goal map, as the published code's input."""
    b = obstacles.shape[0]
    goal_map = torch.zeros_like(obstacles)
    goal_map[torch.arange(b, device=obstacles.device), goals[:, 0], goals[:, 1]] = 1.0
    return torch.stack([1.0 - obstacles, goal_map], dim=1)


def default_gppn_path(size: int = 28) -> Path:
    """Shipped GPPN weights for `size x size` maps: `vinadv/weights/gppn{size}.pt` (may not exist)."""
    return WEIGHTS_DIR / f"gppn{int(size)}.pt"


def save_gppn(model: GPPN, path: str | os.PathLike, record: dict | None = None) -> None:
    """Write `{"format": "vinadv.gppn/1", "config", "state_dict" (float32, CPU), "record"}` to `path` atomically."""
    record = json.loads(json.dumps(dict(record or {})))  # plain JSON types: loadable with weights_only=True
    state = {k: v.detach().to("cpu", torch.float32).contiguous().clone() for k, v in model.state_dict().items()}
    payload = {"format": GPPN_FORMAT, "config": model.config.to_dict(), "state_dict": state, "record": record}
    save_torch(payload, path, mkdir=True)  # a full disk: one line naming the file, no temporary file left


_AUTHORS_HINT = (
    "a checkpoint of the GPPN authors' code is converted by `vinadv gppn import-weights CKPT --k K --out "
    "gppn.pt` (their checkpoints do not store k)"
)


def load_gppn(path: str | os.PathLike | None = None, size: int = 28) -> GPPN:
    """The GPPN in `path` (a vinadv.gppn/1 file), or the shipped weights for `size` when None.

    Sets `record` (the training record) and `weights_path` on the model. Raises InputError naming the file.
    """
    name = weights_file(path, default_gppn_path(size), "GPPN", size)
    try:
        data = torch_load(name, "readable weights file")
    except InputError as exc:
        raise InputError(f"{exc}; {_AUTHORS_HINT}") from None
    if isinstance(data, dict) and data.get("format") is None and ("best_model" in data or "model" in data):
        raise InputError(f"{name}: not a vinadv GPPN weights file; {_AUTHORS_HINT}")
    if not isinstance(data, dict) or data.get("format") != GPPN_FORMAT:
        raise InputError(f"{name}: not a GPPN weights file (expected format {GPPN_FORMAT!r})")
    try:
        config = GPPNConfig(**data["config"])
        model = GPPN(config)
        model.load_state_dict(data["state_dict"])
    except (KeyError, TypeError, RuntimeError) as exc:
        raise InputError(f"{name}: config or state dict do not match a GPPN ({str(exc).splitlines()[0]})") from None
    return as_loaded(model, name, data)
