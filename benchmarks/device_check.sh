#!/usr/bin/env bash
# The device check: one short go on a lent GPU machine (about 6 minutes of its time, the machine's start aside).
#
#     bash benchmarks/device_check.sh            # from the repository root, on the GPU machine
#     STEPS=4 FULL=1000 bash benchmarks/device_check.sh  # the GPPN's exhaustive robustness of 1,000 maps alone
#                                                        # (a second call on the still warm machine, time allowing)
#
# With the device tool, from the session: run(command="bash benchmarks/device_check.sh", timeout_s=600), no carry:
# the machine's own python3 holds PyTorch (CUDA), NumPy, Numba, scikit-learn, tqdm, pytest and pytest-timeout, and
# nothing is installed from the network. vinadv runs from src/ (PYTHONPATH); SQLAlchemy, which the tests' conftest
# imports for the database fixtures, is not there, so the GPU tests run with --noconftest (they use none of it).
#
# Steps, each under its own time limit, each writing under $OUT (a temporary folder without the tool):
# 1. the GPU tests (`pytest -m cuda`): the torch planners and the VIN's forward on cuda against the CPU, differences
#    only at near ties; the exhaustive search and saliency on cuda (cuda_tests.log);
# 2. the command line: `vinadv plan` with --device cuda against the default, on 200 maps (cli.log);
# 3. benchmarks/device.py: plans/s at batch 1, 64, 1024 on the CPU and on cuda, ties on 1,000 maps, robustness of
#    4 maps on both (every strategy and the exhaustive search), for the GPPN and the VIN (device.json);
# 4. with FULL=N: the GPPN's exhaustive robustness of N maps on cuda (full.json).
# STEPS picks some (default "1 2 3 4"; step 4 runs only with FULL).
#
# A dry run on any machine (the GPU tests left out, smaller sizes):
#     DEVICE=cpu PYTHON=.venv/bin/python CLI_MAPS=8 BENCH_ARGS="--batches 1,8 --seconds 0.2 --tie-maps 8
#         --robustness-maps 2" bash benchmarks/device_check.sh
set -u
cd "$(dirname "$0")/.."
OUT=${OUT:-$(mktemp -d)}
mkdir -p "$OUT"
PY=${PYTHON:-python3}
DEVICE=${DEVICE:-cuda}
STEPS=${STEPS:-1 2 3 4}
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

if [ "$DEVICE" = cuda ] && step 1; then
    echo "== 1. GPU tests"
    timeout 200 "$PY" -m pytest --noconftest -p no:cacheprovider -m cuda -q -rA -s tests/planners/test_device.py \
        2>&1 | tee "$OUT/cuda_tests.log"
    [ "${PIPESTATUS[0]}" = 0 ] || status=1
fi

if step 2; then
    echo "== 2. vinadv plan --device $DEVICE against the default"
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

if step 3; then
    echo "== 3. benchmarks/device.py"
    # shellcheck disable=SC2086 (BENCH_ARGS: several words)
    timeout 240 "$PY" benchmarks/device.py --device "$DEVICE" ${BENCH_ARGS:-} --json "$OUT/device.json" \
        > "$OUT/device.log" 2>&1
    [ $? = 0 ] || status=1
    grep -v '^ \|^[{}]' "$OUT/device.log"
fi

if step 4 && [ -n "${FULL:-}" ]; then
    echo "== 4. exhaustive robustness of $FULL maps on $DEVICE (GPPN)"
    timeout 300 "$PY" benchmarks/device.py --device "$DEVICE" --planners gppn --batches 1 --seconds 0.1 --tie-maps 0 \
        --robustness-maps 0 --full-robustness "$FULL" --json "$OUT/full.json" > "$OUT/full.log" 2>&1
    [ $? = 0 ] || status=1
    grep "full robustness" "$OUT/full.log"
fi
echo "device check: done (status $status); files: $(ls "$OUT" | tr '\n' ' ')"
exit $status
