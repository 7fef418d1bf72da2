#!/bin/bash
# LeWM on a lent GPU, ours against upstream 0.1.1, in one device call (bench/bench_wm.py twice: eager, then ours
# through torch.compile).
#
#   bash bench/device_wm.sh prepare   # here: .peer/ (upstream 0.1.1's package + stubs) and .whl/ (py3.12 wheels)
#   device run: bash bench/device_wm.sh run   with carry [".peer", ".whl"]
#
# `prepare` needs ../peer011-venv (bash ../shared/bench/setup_peer011_venv.sh). The device image has torch,
# transformers, h5py, opencv and pyarrow but not gymnasium or loguru (carried as wheels) nor lancedb and hdf5plugin,
# which upstream imports at package import and never uses on this path (stubbed). Both folders must be git-ignored
# (.git/info/exclude) so that they travel only as carried paths.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
prepare)
    PEER_SITE=$(ls -d ../peer011-venv/lib/python3*/site-packages)
    rm -rf .peer .whl
    mkdir -p .peer/peerpkg .peer/stubs/lancedb .whl
    cp -r "$PEER_SITE/stable_worldmodel" .peer/peerpkg/
    find .peer -name __pycache__ -prune -exec rm -rf {} +
    echo "# stub: imported by upstream 0.1.1 at package import, unused here" > .peer/stubs/lancedb/__init__.py
    printf 'class Permutation:  # stub\n    pass\n' > .peer/stubs/lancedb/permutation.py
    cp .peer/stubs/lancedb/__init__.py .peer/stubs/hdf5plugin.py
    cat > .peer/peer.sh <<'PEER'
#!/bin/bash
HERE="$(cd "$(dirname "$0")" && pwd)"
PYTHONPATH="$HERE/stubs:$HERE/peerpkg:${PYTHONPATH:-}" exec "${PEER_PY:-python3}" "$@"
PEER
    chmod +x .peer/peer.sh
    python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
        --platform manylinux_2_28_x86_64 -d .whl gymnasium==1.4.0 farama-notifications loguru
    grep -qx "/.peer/" .git/info/exclude 2>/dev/null || printf '/.peer/\n/.whl/\n' >> .git/info/exclude
    du -sh .peer .whl
    ;;
run)
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
    export PYTHONPATH=/tmp/site PYTHONUNBUFFERED=1 PYTHONWARNINGS=ignore
    OUT=${OUT:-/tmp}
    nvidia-smi --query-gpu=name,driver_version --format=csv,noheader || true
    ARGS="--device cuda --model paper --precision bf16 --envs 1,10 --train-batch 128 --train-steps 20 --repeats 3"
    timeout 200 python3 bench/bench_wm.py --peer "$PWD/.peer/peer.sh" $ARGS 2>&1 | tee "$OUT/wm_bf16.txt" || true
    timeout 350 python3 bench/bench_wm.py --peer '' $ARGS --compile 2>&1 | tee "$OUT/wm_bf16_compile.txt" || true
    ;;
*)
    echo "usage: bash bench/device_wm.sh prepare|run" >&2
    exit 2
    ;;
esac
