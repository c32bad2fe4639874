"""The standard robustness benchmark: frozen, versioned suites (`suites`), one schema-versioned result entry per
(suite, planner, weights) (`entry`), the flags raised on suspicious results (`flags`), and the leaderboard built from
entries (`leaderboard`). `vinadv bench run` and `vinadv bench leaderboard` are its commands."""
