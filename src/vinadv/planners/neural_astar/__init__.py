"""Neural A* (Yonetani et al., "Path Planning using Neural A* Search", ICML 2021), from the paper and the authors'
public repository (omron-sinicx/neural-astar, branch minimal, src/neural_astar/planner/).

- `model`: the CNN encoder (map and start + goal map -> guidance cost map through a sigmoid), its configuration and
  vinadv's weights file for it.
- `differentiable`: the authors' differentiable A* in PyTorch, batched (straight-through selection, Tmax, the
  neighbour filter, backtracking), and the path-map module the saliency attack differentiates.
- `checkpoint`: the authors' Lightning checkpoint read with the allow-list reader and checked key by key.
- `planner`: `NeuralAstarPlanner`, a search planner with an exact mode (the encoder's guidance cost map searched
  by the compiled best-first search of `vinadv.planners.classical.astar`) and the differentiable mode.
- `training`: `train_neural_astar`, the authors' training (their loss, settings and model selection) in the
  training harness (`vinadv.planners.harness`).
"""
