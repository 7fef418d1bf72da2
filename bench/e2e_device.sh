#!/bin/bash
# End to end on one device: collect swm/TwoRoom-v1 (expert), train a tiny LeWM (fp32, bf16), plan with it in swm eval.
# Usage: bash bench/e2e_device.sh [cuda|cpu]   (PYTHON=... picks the interpreter; STABLEWM_HOME the cache)
export STABLEWM_HOME=${STABLEWM_HOME:-/tmp/e2e_home} PYTHONUNBUFFERED=1 PYTHONWARNINGS=ignore
DEV=${1:-cuda}
set -e
${PYTHON:-python3} -m stable_worldmodel.cli collect swm/TwoRoom-v1 --episodes 30 --policy expert --name e2e --num-envs 4 2>&1 | tail -3
${PYTHON:-python3} -m stable_worldmodel.cli train lewm --dataset e2e --preset tiny --steps 200 --device $DEV --name e2e-lewm 2>&1 | tail -4
${PYTHON:-python3} -m stable_worldmodel.cli train lewm --dataset e2e --preset tiny --steps 200 --device $DEV --precision bf16 --name e2e-lewm-bf16 2>&1 | tail -3
${PYTHON:-python3} -m stable_worldmodel.cli eval swm/TwoRoom-v1 --policy wm:e2e-lewm --episodes 8 --num-envs 4 --device $DEV 2>&1 | tail -4
