"""The classical planners: A* and weighted A* (`astar`) and the exact control `optimal` (Dijkstra's policy), the
references a learned planner is measured against."""
