"""`vinadv --help` against a bare Python start, side by side: what the command line costs before any work.

    .venv/bin/python perf/startup.py [--rounds 15] [--json]

Each round starts `python -c pass`, `python -c "import vinadv"` and `vinadv --help` (the command installed beside
this interpreter) as processes of their own, taking turns, and keeps the best wall time of each. Goal (issue 44):
`vinadv --help` under 0.25 s; the ratios to a bare start say how much of it is vinadv's own.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

from common import add_output_arguments, timed_side_by_side


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_output_arguments(parser, rounds=15)
    args = parser.parse_args()
    commands = {
        "python": [sys.executable, "-c", "pass"],
        "import vinadv": [sys.executable, "-c", "import vinadv"],
        "vinadv --help": [str(Path(sys.executable).parent / "vinadv"), "--help"],  # the installed command
    }

    def run(argv: list[str]):
        return lambda: subprocess.run(argv, check=True, capture_output=True)

    best, _ = timed_side_by_side([run(argv) for argv in commands.values()], args.rounds)
    out = {name: round(t, 4) for name, t in zip(commands, best)}
    out["help_over_python"] = round(best[2] / best[0], 2)
    if args.json:
        print(json.dumps(out))
    else:
        for name, t in zip(commands, best):
            print(f"{name:>15}  {t * 1000:7.1f} ms")
        print(f"  vinadv --help is {out['help_over_python']:.2f}x a bare Python start")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
