"""The compiled value-iteration autograd function against PyTorch's own loop (`VIN.q_values`)."""

import pytest
import torch

from vinadv.planners.vin import VIN, VINConfig, value_iteration


def _model(k: int, seed: int, dtype) -> VIN:
    torch.manual_seed(seed)
    model = VIN(VINConfig(k=k, l_h=12, l_q=6)).to(dtype)
    with torch.no_grad():
        model.w.normal_(0, 0.4)  # the default w is 0: values would not propagate at all
    return model


def _grads(model: VIN, q: torch.Tensor, upstream: torch.Tensor) -> dict:
    model.zero_grad()
    (q * upstream).sum().backward()
    return {name: p.grad.clone() for name, p in model.named_parameters() if p.grad is not None}


@pytest.mark.parametrize("size,k", [(8, 10), (11, 7), (16, 20)])
def test_values_and_gradients_equal_torch_float64(size, k):
    model = _model(k, seed=size, dtype=torch.float64)
    gen = torch.Generator().manual_seed(k)
    x = torch.rand(3, 2, size, size, generator=gen, dtype=torch.float64)
    upstream = torch.randn(3, 6, size, size, generator=gen, dtype=torch.float64)
    q_ref = model.q_values(x)
    want = _grads(model, q_ref, upstream)
    q = value_iteration.q_values(model, x)
    got = _grads(model, q, upstream)
    torch.testing.assert_close(q, q_ref, rtol=1e-10, atol=1e-10)  # float64: only the order of the sums differs
    assert set(got) == set(want) == {"h.weight", "h.bias", "r.weight", "q.weight", "w"}
    for name in want:
        torch.testing.assert_close(got[name], want[name], rtol=1e-10, atol=1e-12, msg=name)


def test_float32_close_to_torch_and_batch_split_between_threads():
    model = _model(36, seed=1, dtype=torch.float32)
    x = torch.rand(9, 2, 28, 28, generator=torch.Generator().manual_seed(0))  # >= 2 maps per thread: threaded
    upstream = torch.randn(9, 6, 28, 28, generator=torch.Generator().manual_seed(1))
    want = _grads(model, model.q_values(x), upstream)
    got = _grads(model, value_iteration.q_values(model, x), upstream)
    for name in want:
        scale = want[name].abs().max()
        assert (got[name] - want[name]).abs().max() <= 1e-4 * scale, name


def test_refuses_non_cpu_tensors():
    with pytest.raises(ValueError, match="CPU"):
        value_iteration.value_iteration(torch.zeros(1, 2, 4, 4, device="meta"), torch.zeros(2, 1, 3, 3), 3)
