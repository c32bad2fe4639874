"""TransPath's network (Kirilenko et al., AAAI 2023; AIRI-Institute/TransPath, `models/autoencoder.py`), restated in
PyTorch with the authors' state-dict keys, so their `cf.pth` and `focal.pth` load as they are.

For a 64x64 map (their arrays: 1 = obstacle) and a second channel (`cf`: the goal map; `f`: the start map plus the
goal map), 64 hidden channels throughout:

    encoder.layers.0      conv 5x5 (pad 2), 2 -> 64
    encoder.layers.1..3   residual block, then a stride-2 conv 3x3 (zero pad right and bottom by 1)  -> 8x8
    pos                   + linear(4 -> 64) of a fixed 8x8 grid of coordinates (its 4 channels: x, y, 1-x, 1-y)
    transformer           GroupNorm(32), conv 1x1, 4 blocks (self-attention, self-attention again, feed-forward
                          64 -> 256 -> 64 with GELU; pre-LayerNorm, residual; 4 heads of 16), conv 1x1, + its input
    decoder_pos           + a second positional embedding of the same form
    decoder.layers.0..2   residual block, then nearest-neighbour upsampling x2 and a conv 3x3       -> 64x64
    decoder               GroupNorm(32), x * sigmoid(x), conv 3x3 64 -> 1, tanh

A residual block is GroupNorm(32, eps 1e-6), x * sigmoid(x), conv 3x3, GroupNorm, x * sigmoid(x), dropout, conv 3x3,
plus its input. Dropout is the identity in eval mode, the only mode vinadv plans in. The planner reads
`(output + 1) / 2`: the correction factor k in (0, 1) of the `cf` model, the focal value of the `f` model.

Size: the positional embeddings are fixed 8x8 grids and the encoder halves the map three times, so the model is for
64x64 maps only (the authors' `change_resolution` is not offered).

The weights file (`save_transpath`, `load_transpath`) is `{"format": "vinadv.transpath/1", "mode", "state_dict",
"record"}`: plain tensors and JSON values, read with the allow-list reader.
"""

from __future__ import annotations

import json
import os

import torch
from torch import nn

from vinadv.errors import InputError
from vinadv.outfile import save_torch
from vinadv.planners.neural_astar.model import start_goal_marks
from vinadv.planners.weights import WEIGHTS_DIR, as_loaded, torch_load, weights_file

__all__ = [
    "MODES",
    "SIZE",
    "TRANSPATH_FORMAT",
    "TransPath",
    "load_transpath",
    "network_inputs",
    "positional_grid",
    "save_transpath",
]

TRANSPATH_FORMAT = "vinadv.transpath/1"
#: the map side the model is for (its positional embeddings are 8x8 after three halvings)
SIZE = 64
#: the two models: `cf` (correction factors of the octile heuristic) and `f` (focal values)
MODES = ("cf", "f")
#: the shipped conversions of the authors' weights, by mode
SHIPPED_WEIGHTS = {"cf": WEIGHTS_DIR / "transpath_cf.pt", "f": WEIGHTS_DIR / "transpath_focal.pt"}
HIDDEN = 64
HEADS = 4
BLOCKS = 4
STEPS = 3  # halvings of the encoder, doublings of the decoder
GROUPS = 32
GROUP_EPS = 1e-6


def _swish(x: torch.Tensor) -> torch.Tensor:
    return x * torch.sigmoid(x)  # as the authors write it (not F.silu: the same function, maybe not the same bits)


def _norm() -> nn.GroupNorm:
    return nn.GroupNorm(num_groups=GROUPS, num_channels=HIDDEN, eps=GROUP_EPS, affine=True)


def positional_grid(side: int = SIZE >> STEPS) -> torch.Tensor:
    """`(1, side, side, 4)` float32: the authors' coordinate grid (linspace 0..1 on rows and columns, and 1 minus
    them), which their state dicts hold as `pos.grid` and `decoder_pos.grid`."""
    axis = torch.linspace(0.0, 1.0, side, dtype=torch.float64)
    rows, cols = torch.meshgrid(axis, axis, indexing="ij")
    grid = torch.stack([rows, cols], dim=-1).to(torch.float32)[None]
    return torch.cat([grid, 1.0 - grid], dim=-1)


class ResidualBlock(nn.Module):
    def __init__(self):
        super().__init__()
        self.norm1 = _norm()
        self.conv1 = nn.Conv2d(HIDDEN, HIDDEN, 3, 1, 1)
        self.norm2 = _norm()
        self.dropout = nn.Dropout(0.15)
        self.conv2 = nn.Conv2d(HIDDEN, HIDDEN, 3, 1, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h = self.conv1(_swish(self.norm1(x)))
        h = self.conv2(self.dropout(_swish(self.norm2(h))))
        return x + h


class Down(nn.Module):
    def __init__(self):
        super().__init__()
        self.conv = nn.Conv2d(HIDDEN, HIDDEN, 3, 2, 0)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.conv(nn.functional.pad(x, (0, 1, 0, 1), mode="constant", value=0))


class Up(nn.Module):
    def __init__(self):
        super().__init__()
        self.conv = nn.Conv2d(HIDDEN, HIDDEN, 3, 1, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.conv(nn.functional.interpolate(x, scale_factor=2.0, mode="nearest"))


class Encoder(nn.Module):
    def __init__(self, in_channels: int = 2):
        super().__init__()
        first: list[nn.Module] = [nn.Conv2d(in_channels, HIDDEN, 5, 1, 2)]
        self.layers = nn.ModuleList(first + [nn.Sequential(ResidualBlock(), Down()) for _ in range(STEPS)])

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        for layer in self.layers:
            x = layer(x)
        return x


class Decoder(nn.Module):
    def __init__(self):
        super().__init__()
        self.layers = nn.ModuleList([nn.Sequential(ResidualBlock(), Up()) for _ in range(STEPS)])
        self.norm = _norm()
        self.conv_out = nn.Conv2d(HIDDEN, 1, 3, 1, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        for layer in self.layers:
            x = layer(x)
        return torch.tanh(self.conv_out(_swish(self.norm(x))))


class Positions(nn.Module):
    """`x + linear(grid)`, the grid a fixed parameter of the state dict (`grid`)."""

    def __init__(self):
        super().__init__()
        self.linear = nn.Linear(4, HIDDEN)
        self.grid = nn.Parameter(positional_grid(), requires_grad=False)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.linear(self.grid).moveaxis(3, 1)


class Attention(nn.Module):
    def __init__(self):
        super().__init__()
        self.to_q = nn.Linear(HIDDEN, HIDDEN, bias=False)
        self.to_k = nn.Linear(HIDDEN, HIDDEN, bias=False)
        self.to_v = nn.Linear(HIDDEN, HIDDEN, bias=False)
        self.to_out = nn.Sequential(nn.Linear(HIDDEN, HIDDEN), nn.Dropout(0.15))
        self.scale = (HIDDEN // HEADS) ** -0.5

    def _heads(self, t: torch.Tensor) -> torch.Tensor:
        b, n, _ = t.shape  # (b, n, heads * d) -> (b * heads, n, d)
        return t.reshape(b, n, HEADS, -1).permute(0, 2, 1, 3).reshape(b * HEADS, n, -1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        q, k, v = (self._heads(t) for t in (self.to_q(x), self.to_k(x), self.to_v(x)))
        attn = (torch.einsum("bid,bjd->bij", q, k) * self.scale).softmax(dim=-1)
        out = torch.einsum("bij,bjd->bid", attn, v)
        bh, n, d = out.shape
        out = out.reshape(bh // HEADS, HEADS, n, d).permute(0, 2, 1, 3).reshape(bh // HEADS, n, HEADS * d)
        return self.to_out(out)


class FeedForward(nn.Module):
    def __init__(self):
        super().__init__()
        self.net = nn.Sequential(
            nn.Sequential(nn.Linear(HIDDEN, 4 * HIDDEN), nn.GELU()), nn.Dropout(0.15), nn.Linear(4 * HIDDEN, HIDDEN)
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net(x)


class TransformerBlock(nn.Module):
    def __init__(self):
        super().__init__()
        self.attn1 = Attention()
        self.ff = FeedForward()
        self.attn2 = Attention()  # the authors' cross-attention without a context: self-attention again
        self.norm1 = nn.LayerNorm(HIDDEN)
        self.norm2 = nn.LayerNorm(HIDDEN)
        self.norm3 = nn.LayerNorm(HIDDEN)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = self.attn1(self.norm1(x)) + x
        x = self.attn2(self.norm2(x)) + x
        return self.ff(self.norm3(x)) + x


class SpatialTransformer(nn.Module):
    def __init__(self):
        super().__init__()
        self.norm = _norm()
        self.proj_in = nn.Conv2d(HIDDEN, HIDDEN, 1, 1, 0)
        self.transformer_blocks = nn.ModuleList([TransformerBlock() for _ in range(BLOCKS)])
        self.proj_out = nn.Conv2d(HIDDEN, HIDDEN, 1, 1, 0)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        b, c, h, w = x.shape
        y = self.proj_in(self.norm(x)).permute(0, 2, 3, 1).reshape(b, h * w, c)  # the authors' layouts, as einops
        for block in self.transformer_blocks:
            y = block(y)
        y = y.reshape(b, h, w, c).permute(0, 3, 1, 2)
        return self.proj_out(y) + x


def network_inputs(obstacles: torch.Tensor, starts: torch.Tensor | None, goals: torch.Tensor) -> torch.Tensor:
    """`(B, 2, N, N)`: the map (1 = obstacle, the authors' arrays) and the goal map (`starts` None, the `cf` model's
    input) or the start map plus the goal map (the `f` model's; 2 at a start that is the goal)."""
    return torch.stack([obstacles, start_goal_marks(obstacles, starts, goals)], dim=1)


class TransPath(nn.Module):
    """The authors' `Autoencoder` (module doc) for one `mode` (`cf` or `f`). `forward(obstacles (B, 64, 64) float
    1/0, starts (B, 2) or None, goals (B, 2)) -> (B, 64, 64)`: `(network + 1) / 2`, the correction factors (`cf`; the
    starts are not read) or the focal values (`f`)."""

    def __init__(self, mode: str = "cf"):
        super().__init__()
        if mode not in MODES:
            raise InputError(f"TransPath mode {mode!r}: expected one of {', '.join(MODES)}", "mode")
        self.mode = mode
        self.encoder = Encoder()
        self.pos = Positions()
        self.transformer = SpatialTransformer()
        self.decoder_pos = Positions()
        self.decoder = Decoder()

    def network(self, inputs: torch.Tensor) -> torch.Tensor:
        """The authors' `forward`: `(B, 2, 64, 64)` inputs to `(B, 1, 64, 64)` in (-1, 1)."""
        x = self.decoder_pos(self.transformer(self.pos(self.encoder(inputs))))
        return self.decoder(x)

    def forward(self, obstacles: torch.Tensor, starts: torch.Tensor | None, goals: torch.Tensor) -> torch.Tensor:
        if obstacles.shape[-1] != SIZE or obstacles.shape[-2] != SIZE:
            n = obstacles.shape[-1]
            raise InputError(f"TransPath is for {SIZE}x{SIZE} maps (8x8 positional embeddings), the maps are {n}x{n}")
        inputs = network_inputs(obstacles, starts if self.mode == "f" else None, goals)
        return (self.network(inputs) + 1) / 2

    def outputs(self, obstacles: torch.Tensor, starts: torch.Tensor | None, goals: torch.Tensor) -> torch.Tensor:
        return self(obstacles, starts, goals)[:, 0]


def save_transpath(model: TransPath, path: str | os.PathLike, record: dict | None = None) -> None:
    """Write `{"format": "vinadv.transpath/1", "mode", "state_dict" (CPU), "record"}` to `path` atomically."""
    record = json.loads(json.dumps(dict(record or {})))  # plain JSON types: loadable with weights_only=True
    state = {k: v.detach().to("cpu").contiguous().clone() for k, v in model.state_dict().items()}
    save_torch(
        {"format": TRANSPATH_FORMAT, "mode": model.mode, "state_dict": state, "record": record}, path, mkdir=True
    )


_IMPORT_HINT = "the authors' weights are converted by `vinadv transpath import-weights FILE --mode cf|f --out OUT`"


def load_transpath(path: str | os.PathLike | None = None, mode: str = "cf") -> TransPath:
    """The TransPath model in `path` (a vinadv.transpath/1 file), or the shipped one of `mode` when None, in eval
    mode; a file of the other mode is refused. Sets `record` and `weights_path`. Raises InputError naming the file."""
    if mode not in MODES:
        raise InputError(f"TransPath mode {mode!r}: expected one of {', '.join(MODES)}", "mode")
    name = weights_file(path, SHIPPED_WEIGHTS[mode], {"cf": "transpath-cf", "f": "transpath-focal"}[mode], SIZE)
    data = torch_load(name, "readable weights file")
    if isinstance(data, dict) and "format" not in data and "encoder.layers.0.weight" in data:
        raise InputError(f"{name}: the authors' state dict, not a vinadv TransPath weights file; {_IMPORT_HINT}")
    if not isinstance(data, dict) or data.get("format") != TRANSPATH_FORMAT:
        raise InputError(f"{name}: not a TransPath weights file (expected format {TRANSPATH_FORMAT!r})")
    if data.get("mode") != mode:
        raise InputError(f"{name}: TransPath weights of mode {data.get('mode')!r}, expected {mode!r}")
    model = TransPath(mode)
    try:
        model.load_state_dict(data["state_dict"])
    except (KeyError, TypeError, RuntimeError) as exc:
        raise InputError(f"{name}: the state dict does not match TransPath's ({str(exc).splitlines()[0]})") from None
    return as_loaded(model, name, data)
