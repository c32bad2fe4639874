#!/usr/bin/env bash
# The device check: one short go on a lent GPU machine, at most about 9.5 minutes of its time (the machine's start
# aside), the figures issue 36 asks for first, each step under its own time limit, each writing under $OUT (a
# temporary folder without the tool), the JSON saved as it goes (a step cut at its limit keeps what it measured):
#
#     bash perf/device_check.sh              # from the repository root, on the GPU machine: steps 1-4
#     STEPS="5 6" bash perf/device_check.sh  # the rest, a second call on the still warm machine, time allowing
#
# With the device tool, from the session: run(command="bash perf/device_check.sh", timeout_s=600), no carry:
# the machine's own python3 holds PyTorch (CUDA), NumPy, Numba, scikit-learn, tqdm, pytest and pytest-timeout, and
# nothing is installed from the network. vinadv runs from src/ (PYTHONPATH); SQLAlchemy, which the tests' conftest
# imports for the database fixtures, is not there, so the GPU tests run with --noconftest (they use none of it).
#
# Steps (limits in seconds; 1-4 add up to 565, under the tool's 600 a command):
# 1. (170) plans per second at batch 1, 64 and 1,024 on the CPU and on cuda, GPPN (octile 28x28 maps) and Neural A*
#    (moore 28x28 maps), by perf/device.py (speed_gppn.json, speed_neural_astar.json);
# 2. (240) the GPPN's exhaustive robustness of FULL maps (default 1,000: issue 36's target, under 5 minutes on one
#    H100-class GPU) on cuda, 100 maps a call, full.json rewritten after each: cut at the limit, it still gives the
#    maps done and their seconds;
# 3. (95) the GPU tests (`pytest -m cuda`): the torch planners and the VIN's forward on cuda against the CPU,
#    differences only at near ties; the exhaustive search and saliency on cuda (cuda_tests.log);
# 4. (60) where src/vinadv/weights/vin64.pt ships: the 64x64 VIN's PyTorch forward on cuda on the 1,000 held-out
#    64x64 maps, with its success-by-path-length curve (vin64_cuda.json, vin64_cuda_by_length.svg), to set beside
#    the engine's committed vin64.metrics.json (the same maps, the CPU);
# 5. (90) the command line: `vinadv plan` with --device cuda against the default, on 200 maps (cli.log);
# 6. (240) perf/device.py for the GPPN and the VIN: ties on 1,000 maps and the robustness suite of 4 maps on
#    the CPU and on cuda (device.json).
# 7. (ENTRY_SECONDS, default 570) issue 34's bench entry of the GPPN on vin28-v1 on cuda (vin28-v1.gppn.json): a
#    call of its own, `STEPS=7`; commit the entry under docs/results/bench/ and refresh the leaderboard's index;
# 8. (ENTRY_SECONDS each) the same for the MP learned planners on mpd32-v2 (`STEPS=8`, MPD_DIR the six MP files:
#    copy them to the git-ignored .mpd/ and carry it; MPD_PLANNERS, default gppn-mpd32 (the one without a full
#    entry), one call each where the time allows one; MPD_SUITE, default mpd32-v2).
# STEPS picks some (default "1 2 3 4").
#
# A dry run on any machine (the GPU tests left out, small sizes):
#     DEVICE=cpu PYTHON=.venv/bin/python FULL=2 N64=5 CLI_MAPS=8 STEPS="1 2 4 5 6" BATCHES=1,8 BENCH_SECONDS=0.2 \
#         BENCH_ARGS="--tie-maps 8 --robustness-maps 1" bash perf/device_check.sh
set -u
cd "$(dirname "$0")/.."
OUT=${OUT:-$(mktemp -d)}
mkdir -p "$OUT"
PY=${PYTHON:-python3}
DEVICE=${DEVICE:-cuda}
STEPS=${STEPS:-1 2 3 4}
FULL=${FULL:-1000}
N64=${N64:-1000}
BATCHES=${BATCHES:-1,64,1024}
BENCH_SECONDS=${BENCH_SECONDS:-2}
step() { case " $STEPS " in *" $1 "*) return 0 ;; *) return 1 ;; esac; }
export PYTHONPATH="$PWD/src:$PWD" PYTHONUNBUFFERED=1 PYTHONDONTWRITEBYTECODE=1
export VINADV_CACHE_DIR="${VINADV_CACHE_DIR:-$(mktemp -d)}"
echo "device check: results under $OUT"

nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader 2>&1 | tee "$OUT/gpu.txt"
"$PY" -c "import torch; print('torch', torch.__version__, 'cuda', torch.cuda.is_available())"
if [ "$DEVICE" = cuda ] && ! "$PY" -c "import sys, torch; sys.exit(0 if torch.cuda.is_available() else 1)"; then
    echo "device check: PyTorch sees no CUDA GPU here; nothing to check (DEVICE=cpu for a dry run)" >&2
    exit 2
fi
status=0

if step 1; then
    echo "== 1. plans per second, GPPN and Neural A*, on the CPU and on $DEVICE"
    timeout 85 "$PY" perf/device.py --device "$DEVICE" --planners gppn \
        --batches "$BATCHES" --seconds "$BENCH_SECONDS" --tie-maps 0 --robustness-maps 0 \
        --json "$OUT/speed_gppn.json" > "$OUT/speed_gppn.log" 2>&1 || status=1
    timeout 85 "$PY" perf/device.py --device "$DEVICE" --planners neural-astar --moves moore \
        --batches "$BATCHES" --seconds "$BENCH_SECONDS" --tie-maps 0 --robustness-maps 0 \
        --json "$OUT/speed_neural_astar.json" > "$OUT/speed_neural_astar.log" 2>&1 || status=1
    grep -h " batch " "$OUT/speed_gppn.log" "$OUT/speed_neural_astar.log"
fi

if step 2; then
    echo "== 2. exhaustive robustness of $FULL maps on $DEVICE (GPPN)"
    timeout 240 "$PY" perf/device.py --device "$DEVICE" --planners gppn --batches 1 --seconds 0.1 --tie-maps 0 \
        --robustness-maps 0 --full-robustness "$FULL" --json "$OUT/full.json" > "$OUT/full.log" 2>&1 || status=1
    grep "full robustness" "$OUT/full.log" | tail -1
fi

if [ "$DEVICE" = cuda ] && step 3; then
    echo "== 3. GPU tests"
    timeout 95 "$PY" -m pytest --noconftest -p no:cacheprovider -m cuda -q -rA -s tests/planners/test_device.py \
        2>&1 | tee "$OUT/cuda_tests.log" | tail -5
    [ "${PIPESTATUS[0]}" = 0 ] || status=1
fi

if step 4 && [ -f src/vinadv/weights/vin64.pt ]; then
    echo "== 4. the 64x64 VIN's forward on $DEVICE, $N64 held-out maps, success by path length"
    timeout 60 "$PY" -m vinadv.cli eval --planner vin --size 64 --n "$N64" --seed 1000 --device "$DEVICE" \
        --protocol vinadv --quiet --out "$OUT/vin64_cuda.json" --figure "$OUT/vin64_cuda_by_length.svg" \
        2>&1 | tee "$OUT/vin64_cuda.log" | head -3
    [ "${PIPESTATUS[0]}" = 0 ] || status=1
fi

if step 5; then
    echo "== 5. vinadv plan --device $DEVICE against the default"
    DEVICE=$DEVICE CLI_MAPS=${CLI_MAPS:-200} timeout 90 "$PY" - <<'EOF' 2>&1 | tee "$OUT/cli.log"
import json, os, tempfile, time
from vinadv.cli import main
from vinadv.planners.pathset import PathSet

d, device_name = tempfile.mkdtemp(), os.environ["DEVICE"]
maps = os.path.join(d, "maps.npz")
n = os.environ["CLI_MAPS"]
assert main(["maps", "generate", "--n", n, "--size", "28", "--seed", "1000", "--out", maps, "--quiet"]) == 0
for planner in ("gppn", "vin"):
    got = {}
    for device in (None, device_name):
        out = os.path.join(d, f"{planner}-{device}.npz")
        t0 = time.perf_counter()
        assert main(["plan", "--maps", maps, "--planner", planner, "--out", out, "--quiet",
                     *(["--device", device] if device else [])]) == 0
        got[device] = (PathSet.load(out), round(time.perf_counter() - t0, 2))
    (a, ta), (b, tb) = got[None], got[device_name]
    same = a.paths.same_as(b.paths)
    print(json.dumps({"planner": planner, "paths": len(same), "differing": int((~same).sum()),
                      "seconds": {"default": ta, device_name: tb}}))
EOF
    [ "${PIPESTATUS[0]}" = 0 ] || status=1
fi

if step 6; then
    echo "== 6. perf/device.py: ties on 1,000 maps and the robustness suite of 4 maps, GPPN and VIN"
    # shellcheck disable=SC2086 (BENCH_ARGS: several words)
    timeout 240 "$PY" perf/device.py --device "$DEVICE" --batches 1 --seconds 0.1 ${BENCH_ARGS:-} \
        --json "$OUT/device.json" > "$OUT/device.log" 2>&1
    [ $? = 0 ] || status=1
    grep -v '^ \|^[{}]' "$OUT/device.log"
fi
if step 7; then
    echo "== 7. issue 34's GPU entry: the GPPN on the full vin28-v1 suite, on $DEVICE (about 20 h on the 2-core CPU)"
    # no --db: the device's python has no SQLAlchemy, so a run cut at the limit keeps nothing but its log
    timeout "${ENTRY_SECONDS:-570}" "$PY" -m vinadv.cli bench run --suite "${GPPN_SUITE:-vin28-v1}" --planner gppn \
        --device "$DEVICE" --out "$OUT/${GPPN_SUITE:-vin28-v1}.gppn.json" > "$OUT/entry_gppn.log" 2>&1
    [ $? = 0 ] || status=1
    tail -n 3 "$OUT/entry_gppn.log"
fi

if step 8; then
    # MPD_DIR: the six MP files, e.g. copied to the git-ignored .mpd/ and carried (run(carry=[".mpd"]));
    # MPD_PLANNERS: the MP learned planners without a full entry (one call each if ENTRY_SECONDS allows only one)
    for planner in ${MPD_PLANNERS:-gppn-mpd32}; do
        echo "== 8. issue 46's GPU entry: $planner on the full ${MPD_SUITE:-mpd32-v2} suite, on $DEVICE (hours on the 2-core CPU)"
        timeout "${ENTRY_SECONDS:-570}" "$PY" -m vinadv.cli bench run --suite "${MPD_SUITE:-mpd32-v2}" \
            --planner "$planner" --data "${MPD_DIR:-.mpd}" --device "$DEVICE" \
            --out "$OUT/${MPD_SUITE:-mpd32-v2}.$planner.json" > "$OUT/entry_$planner.log" 2>&1
        [ $? = 0 ] || status=1
        tail -n 3 "$OUT/entry_$planner.log"
    done
fi
echo "device check: done (status $status); files: $(ls "$OUT" | tr '\n' ' ')"
exit $status
