"""TransPath (Kirilenko, Andreychuk, Panov, Yakovlev, "TransPath: Learning Heuristics For Grid-Based Pathfinding via
Transformers", AAAI 2023), from the authors' public repository (AIRI-Institute/TransPath, MIT) and their weights.

- `model`: the authors' network (a ResNet-style encoder to 8x8, positional embeddings, four transformer blocks, a
  mirrored decoder) with their state-dict keys, for 64x64 maps; vinadv's weights file for it.
- `checkpoint`: the authors' `cf.pth` / `focal.pth` read with the allow-list reader and checked key by key.
- `search`: their search (`modules/planners.py`) as a compiled best-first search in their float32 arithmetic: A*
  with the octile heuristic divided by the correction factor (`cf`), focal search on the focal values (`f`).
- `differentiable`: the same search in PyTorch, batched, with a straight-through selection (the differentiable mode,
  for the saliency attack's gradients).
- `planner`: `TransPathPlanner`, the search planners `transpath-cf` and `transpath-focal`, and the registry's loader.
"""
