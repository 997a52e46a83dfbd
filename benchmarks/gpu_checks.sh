#!/usr/bin/env bash
# The GPU measurements of docs/performance.md in one run on one CUDA machine, each bounded by
# a timeout so that a slow or hung part leaves the others' results (about 9 minutes at most,
# the first part compiling MuJoCo Warp's and the renderer's kernels into the shared cache):
#   syncs       the main job's host waits per step and per scripted plan (torch's sync check), 1024 envs
#   throughput  PushCube-v1 env-steps/s and the ratio to raw MuJoCo Warp at 1024 and 4096 envs
#   camera      PushCube-v1 with a 128x128 Warp camera in its observation, 1024 and 4096 envs
#   main_job    the data-generation job recorded end to end, with its phases, 64, 256 and 1024 envs
# Each writes OUT_DIR/<part>.json and OUT_DIR/<part>.log.
#
# Usage: bash benchmarks/gpu_checks.sh OUT_DIR [PYTHON]
set -u
out=${1:?usage: bash benchmarks/gpu_checks.sh OUT_DIR [PYTHON]}
py=${2:-.venv/bin/python}
mkdir -p "$out"
export PYTHONUNBUFFERED=1 HF_HUB_OFFLINE=1 HF_DATASETS_OFFLINE=1

part() {
    local name=$1 limit=$2
    shift 2
    echo "== $name (at most ${limit} s)"
    timeout "$limit" "$py" "$@" --out "$out/$name.json" >"$out/$name.log" 2>&1
    local rc=$?
    tail -n 12 "$out/$name.log"
    echo "== $name: exit $rc"
}

part syncs 150 benchmarks/gpu_main_job.py --case syncs --device cuda --num-envs 1024
part throughput 100 benchmarks/gpu_throughput.py --device cuda --num-envs 1024 4096 --repeats 3
part camera 60 benchmarks/gpu_main_job.py --case camera --device cuda --num-envs 1024 4096
part main_job 230 benchmarks/gpu_main_job.py --device cuda --num-envs 64 256 1024
