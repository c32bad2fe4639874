"""GPPN: the forward against a plain implementation of the published equations, the weights file, the keys,
widening."""

import numpy as np
import pytest
import torch

from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.interop.checkpoints import GPPN_KEYS
from vinadv.planners.gppn import GPPN, MAX_KERNEL, MAX_WIDTH, GPPNConfig, load_gppn, save_gppn, widen_gppn


def plain_gppn(model: GPPN, free: torch.Tensor, goal_map: torch.Tensor) -> torch.Tensor:
    """Lee et al. (2018) written out: conv layers on (B, C, N, N) maps, an LSTM cell applied at every cell with
    its own gates spelled out (i, f, g, o in PyTorch's order), k - 1 steps, a 1x1 policy conv."""
    sd = dict(model.named_parameters())  # live parameters: gradients reach them
    f = model.config.f
    x = torch.stack([free, goal_map], dim=1)
    hid = torch.nn.functional.conv2d(x, sd["hid.weight"], sd["hid.bias"], padding=1)
    h = torch.nn.functional.conv2d(hid, sd["h0.weight"], sd["h0.bias"], padding=1)
    c = torch.nn.functional.conv2d(hid, sd["c0.weight"], sd["c0.bias"], padding=1)
    w_ih, w_hh = sd["lstm.weight_ih"], sd["lstm.weight_hh"]  # (4 l_h, 1), (4 l_h, l_h)
    b_ih, b_hh = sd["lstm.bias_ih"], sd["lstm.bias_hh"]
    l_h = h.shape[1]
    for _ in range(model.config.k - 1):
        inp = torch.nn.functional.conv2d(h, sd["conv.weight"], sd["conv.bias"], padding=f // 2)  # (B, 1, N, N)
        # gates[b, :, i, j] = W_ih inp[b, :, i, j] + b_ih + W_hh h[b, :, i, j] + b_hh
        gates = (
            torch.einsum("gc,bcij->bgij", w_ih, inp)
            + torch.einsum("gc,bcij->bgij", w_hh, h)
            + (b_ih + b_hh)[None, :, None, None]
        )
        i_g, f_g, g_g, o_g = (gates[:, q * l_h : (q + 1) * l_h] for q in range(4))
        c = torch.sigmoid(f_g) * c + torch.sigmoid(i_g) * torch.tanh(g_g)
        h = torch.sigmoid(o_g) * torch.tanh(c)
    return torch.nn.functional.conv2d(h, sd["policy.weight"])


@pytest.mark.parametrize("k,l_h,f", [(5, 8, 3), (8, 6, 5), (1, 4, 1)])
def test_forward_matches_the_published_equations(k, l_h, f):
    torch.manual_seed(k)
    model = GPPN(GPPNConfig(k=k, l_h=l_h, f=f)).double()
    maps = generate_maps(6, 12, seed=1, n_starts=1)
    obstacles = torch.from_numpy(maps.obstacles.astype(np.float64))
    goals = torch.from_numpy(maps.goals)
    goal_map = torch.zeros_like(obstacles)
    for b, (r, c) in enumerate(maps.goals):
        goal_map[b, r, c] = 1.0
    with torch.no_grad():
        got = model(obstacles, goals)
        want = plain_gppn(model, 1.0 - obstacles, goal_map)
    assert got.shape == (6, 8, 12, 12)
    torch.testing.assert_close(got, want, rtol=1e-10, atol=1e-10)


def test_gradients_match_the_published_equations():
    torch.manual_seed(0)
    model = GPPN(GPPNConfig(k=6, l_h=5, f=3)).double()
    maps = generate_maps(3, 10, seed=2, n_starts=1)
    obstacles = torch.from_numpy(maps.obstacles.astype(np.float64))
    goal_map = torch.zeros_like(obstacles)
    goal_map[np.arange(3), maps.goals[:, 0], maps.goals[:, 1]] = 1.0
    weights = torch.randn(3, 8, 10, 10, dtype=torch.float64)
    (model(obstacles, torch.from_numpy(maps.goals)) * weights).sum().backward()
    got = {k: p.grad.clone() for k, p in model.named_parameters()}
    model.zero_grad()
    (plain_gppn(model, 1.0 - obstacles, goal_map) * weights).sum().backward()
    for k, p in model.named_parameters():
        torch.testing.assert_close(got[k], p.grad, rtol=1e-9, atol=1e-10, msg=k)


def test_state_dict_keys_are_those_of_the_public_code():
    keys = set(GPPN(GPPNConfig(l_h=4)).state_dict())
    assert keys == set(GPPN_KEYS)  # the keys of the authors' checkpoints, which interop reads


def test_save_and_load_round_trip(tmp_path):
    model = GPPN(GPPNConfig(k=4, l_h=6, f=5))
    save_gppn(model, tmp_path / "g.pt", {"note": "x"})
    back = load_gppn(tmp_path / "g.pt")
    assert back.config == model.config and back.record == {"note": "x"}
    for k, v in model.state_dict().items():
        torch.testing.assert_close(back.state_dict()[k], v)


def test_bad_files_are_refused(tmp_path):
    with pytest.raises(InputError, match="no such weights file"):
        load_gppn(tmp_path / "missing.pt")
    (tmp_path / "junk.pt").write_bytes(b"not torch")
    with pytest.raises(InputError, match="junk.pt: not a readable"):
        load_gppn(tmp_path / "junk.pt")
    torch.save({"h.weight": torch.zeros(1)}, tmp_path / "vin.pt")
    with pytest.raises(InputError, match="not a GPPN weights file"):
        load_gppn(tmp_path / "vin.pt")
    with pytest.raises(InputError, match="kernel f must be odd"):
        GPPN(GPPNConfig(f=4))


def _random_gppn(k: int, l_h: int, f: int, seed: int) -> GPPN:
    torch.manual_seed(seed)
    model = GPPN(GPPNConfig(k=k, l_h=l_h, f=f)).double()
    with torch.no_grad():  # larger weights than the default start, so a wrong split would show in the logits
        for p in model.parameters():
            p.mul_(3.0)
    return model


@pytest.mark.parametrize("old,new", [(4, 4), (4, 6), (4, 8), (3, 11)])
def test_widening_without_noise_keeps_the_logits(old, new):
    model = _random_gppn(k=7, l_h=old, f=3, seed=new)
    wide = widen_gppn(model, new, noise=0.0, seed=1).double()
    assert wide.config == GPPNConfig(k=7, l_h=new, f=3)
    maps = generate_maps(5, 12, seed=3, n_starts=1)
    obstacles, goals = torch.from_numpy(maps.obstacles.astype(np.float64)), torch.from_numpy(maps.goals)
    goal_map = torch.zeros_like(obstacles)
    goal_map[np.arange(5), maps.goals[:, 0], maps.goals[:, 1]] = 1.0
    with torch.no_grad():
        want = plain_gppn(model, 1.0 - obstacles, goal_map)
        torch.testing.assert_close(plain_gppn(wide, 1.0 - obstacles, goal_map), want, rtol=1e-5, atol=1e-5)
        torch.testing.assert_close(wide(obstacles, goals), want, rtol=1e-5, atol=1e-5)


def test_widening_with_noise_changes_only_the_added_channels_incoming_weights():
    model = _random_gppn(k=5, l_h=4, f=3, seed=0)
    plain, noisy = widen_gppn(model, 7, noise=0.0, seed=2), widen_gppn(model, 7, noise=0.01, seed=2)
    a, b = plain.state_dict(), noisy.state_dict()
    for key in ("conv.weight", "conv.bias", "policy.weight"):  # read the channels: split, no noise
        torch.testing.assert_close(a[key], b[key])
    for key in ("hid.weight", "h0.weight", "c0.weight", "lstm.weight_hh", "lstm.bias_ih"):
        rows_a = a[key].reshape(-1, 7, *a[key].shape[1:])  # (gate blocks, channels, ...)
        rows_b = b[key].reshape(-1, 7, *b[key].shape[1:])
        torch.testing.assert_close(rows_b[:, :4], rows_a[:, :4], msg=key)  # the old channels keep their weights
        assert not torch.equal(rows_b[:, 4:], rows_a[:, 4:]), key
    maps = generate_maps(4, 10, seed=1, n_starts=1)
    obstacles, goals = torch.from_numpy(maps.obstacles.astype(np.float32)), torch.from_numpy(maps.goals)
    with torch.no_grad():
        base, moved = model.float()(obstacles, goals), noisy(obstacles, goals)
    assert 0 < float((base - moved).abs().max()) < 0.5


def test_widening_refuses_a_narrower_width_and_bad_noise(tmp_path, capsys):
    model = GPPN(GPPNConfig(k=3, l_h=4, f=3))
    with pytest.raises(InputError, match="l_h must be at least the model's width 4 to widen it, got 3") as err:
        widen_gppn(model, 3)
    assert err.value.parameters == ("l_h",)
    for noise in (-0.1, float("nan")):
        with pytest.raises(InputError, match="noise must be >= 0"):
            widen_gppn(model, 6, noise=noise)
    save_gppn(model, tmp_path / "g.pt")
    assert main(["gppn", "widen", str(tmp_path / "g.pt"), "--l-h", "2", "--out", str(tmp_path / "w.pt")]) == 2
    assert "--l-h must be at least" in capsys.readouterr().err
    assert not (tmp_path / "w.pt").exists()
    assert main(["gppn", "widen", str(tmp_path / "g.pt"), "--l-h", "6", "--out", str(tmp_path / "w.pt"), "--json"]) == 0
    wide = load_gppn(tmp_path / "w.pt")
    assert wide.config.l_h == 6 and wide.record["widened_from"]["config"]["l_h"] == 4


def test_a_width_or_kernel_past_the_limit_is_refused_before_anything_is_made(tmp_path, capsys):
    # a width of millions took every byte of memory (the process was killed) before this check
    model = GPPN(GPPNConfig(k=3, l_h=4, f=3))
    with pytest.raises(InputError, match=f"l_h must be at most {MAX_WIDTH}, got {MAX_WIDTH + 1}") as err:
        widen_gppn(model, MAX_WIDTH + 1)
    assert err.value.parameters == ("l_h",)
    assert widen_gppn(model, 6, noise=0).config.l_h == 6
    for config in (GPPNConfig(l_h=10**7), GPPNConfig(f=MAX_KERNEL + 2)):
        with pytest.raises(InputError, match="at most"):
            GPPN(config)
    save_gppn(model, tmp_path / "g.pt")
    out = tmp_path / "w.pt"
    assert main(["gppn", "widen", str(tmp_path / "g.pt"), "--l-h", str(10**7), "--out", str(out)]) == 2
    assert capsys.readouterr().err == f"vinadv: error: GPPN --l-h must be at most {MAX_WIDTH}, got 10000000\n"
    assert not out.exists()
