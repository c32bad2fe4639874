"""PyTorch's own value map and policy for one map, bit for bit, without PyTorch: how the engine settles near ties.

Where two logits of a cell are within rounding of each other, the engine must take the reference's decision, which is
made by PyTorch's float32 arithmetic: a batch-1 `VIN.q_values`, then `fc` at the cell. That call costs ~3 ms at
28x28 on a quiet core, nearly all of it the overhead of the 3k small ops of the loop, and much more on a busy
machine: with 2 PyTorch threads and another process holding a core, each small op waits for OpenMP threads (the h
layer alone took 23 ms instead of 0.1 ms). Each op is cheap and simple to replay:

- h, the 2 -> l_h 3x3 convolution with bias, and the 1 -> l_q 3x3 convolutions (the first q layer on r, then w on
  v at every step) go through ATen's `slow_conv2d` at batch size 1: im2col (exact copies, zero padding), then a BLAS
  sgemm with K = 9 x input channels, which builds each output as a chain over the taps (input channel, kernel row,
  kernel column), starting from 0, then adds the bias; per output channel the chain is either fused multiply-adds
  or multiply-then-add, depending on the BLAS kernel (MKL, 1 -> l_q on 2 threads: blocks of 8 channels fused, the
  rest not; on 1 thread: all fused; h: all fused on 1 and 2 threads);
- r, the 1x1 convolution l_h -> 1, is an sgemm with M = 1: one or two chains over the l_h channels (MKL on 2
  threads: fused, split at 128; on 1 thread: one unfused chain);
- `q_r + conv` is one float32 add and the max over channels is exact.

`replay_q_values` replays all of it in compiled loops that round exactly as above. Which chains is measured, never
assumed: `conv_modes` and `sum_order` run PyTorch's convolutions on random data once for each (map size, widths,
PyTorch threads) and keep the chains that reproduce them bit for bit; the first `VERIFY_MAPS` maps of each setting
are also compared whole with `VIN.q_values`. If a check fails, that setting uses `VIN.q_values` itself (slow, but
exact); where only r's order is not found (MKL on 2 threads at 32x32 and 64x64), PyTorch computes r alone from the
replayed h, one small op per map, and the rest is replayed. Elsewhere the only PyTorch calls are those checks, a few
per setting and process.

"Bit for bit" means: equal to what PyTorch computes with the caller's `torch.get_num_threads()`, the setting the
reference planner runs under (PyTorch's own float32 results depend on its thread count); in a process that has not
loaded PyTorch, with the thread count PyTorch starts with there.

What was measured and checked is kept on disk per machine (`cache_path()`, keyed by `machine_key()`: PyTorch's
version, the CPU, the cores and the BLAS/OpenMP environment variables), so a later process replays without loading
PyTorch at all: `vinadv run` with the VIN then never imports it. Delete the file to measure again.

`exact_actions` then decides every cell of a map from that value map: in float64 where the two best logits are
further apart than any float32 evaluation of `fc` could move them (a rigorous bound), else (rare: about 50 cells in
a 5,000-map run) with `fc` at the cell replayed as PyTorch computes it, a (1, l_q) x (l_q, A) product whose sum
follows a fixed tree that is neither a chain nor any textbook order (MKL on 1 and 2 threads, l_q = 10: three
products chained, then four lanes, then the lanes summed in halves). `fc_order` reads that tree off PyTorch with
exact probes (a +B and a -B product cancel exactly and a 1 survives only if the two meet before it) and decides
on random data whether the products are fused into the adds; the first `VERIFY_CELLS` cells of each setting are
also compared with PyTorch's own `fc`.

The modules: `cache` (what was measured and checked: `ReplayCache`, its process-wide instance `CACHE`, the file on
disk), `kernels` (the compiled chains), `orders` (`conv_modes`, `sum_order`), `fc` (`fc_order` and the replayed
`fc`), `actions` (`replay_q_values`, `exact_actions`).
"""

from vinadv.planners.vin.replay.actions import best_and_gap, exact_actions, replay_q_values
from vinadv.planners.vin.replay.cache import CACHE, ReplayCache, cache_path, machine_key, torch_threads_now
from vinadv.planners.vin.replay.fc import fc_order
from vinadv.planners.vin.replay.orders import conv_modes, sum_order

__all__ = [
    "CACHE",
    "ReplayCache",
    "best_and_gap",
    "cache_path",
    "conv_modes",
    "exact_actions",
    "fc_order",
    "machine_key",
    "replay_q_values",
    "sum_order",
    "torch_threads_now",
]
