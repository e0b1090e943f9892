#!/usr/bin/env bash
# Every real-GPU figure of docs/gpu.md and docs/performance.md in one run (at most 8 minutes of
# device time on an H100/H200 with a 16-core host), each GPU run beside the host's cores:
#
#   scripts/gpu-figures.sh [BINARY] [OUT]
#
# BINARY: a release build of `radiosity` (default target/release/radiosity); OUT: where the JSON
# reports and the log go (default gpu-figures/). Needs /usr/bin/time. Each step has a time limit,
# so that one slow step cannot take the others' time; a step that runs out says so in the log.
set -u
bin=${1:-target/release/radiosity}
out=${2:-gpu-figures}
mkdir -p "$out"
log="$out/log.txt"
: >"$log"

# step NAME LIMIT_SECONDS ARGS...: runs `radiosity ARGS --json OUT/NAME.json` under /usr/bin/time.
step() {
    local name=$1 limit=$2
    shift 2
    echo "== $name: radiosity $*" | tee -a "$log"
    /usr/bin/time -f "$name: %e s wall, %M KiB peak" timeout "$limit" \
        "$bin" "$@" --json "$out/$name.json" >>"$log" 2>"$out/$name.stderr"
    local rc=$?
    tail -n 1 "$out/$name.stderr" | tee -a "$log"
    [ $rc -eq 124 ] && echo "$name: ran past $limit s" | tee -a "$log"
    return 0
}

{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader 2>/dev/null \
    || echo "no nvidia-smi"; lscpu | grep -E "Model name|^CPU\(s\)"; } | tee -a "$log"

step gpu-check 30 gpu-check --samples 1000000
# Five-piece refine 6, K kept on the device, against the host's cores (whole runs).
for backend in cpu gpu; do
    step "five-piece-6-dense-$backend" 60 solve --scene five-piece --refine 6 --operator dense \
        --solver iterative --backend "$backend"
done
# The louvre window at refine 5: the device clips the elements of faces seen in part.
step louvre-window-5 90 bench --scene examples/louvre-window.toml --refine 5 --backends cpu,gpu \
    --repeats 1
# Five-piece refine 8, compressed (n = 655 360).
for backend in cpu gpu; do
    step "five-piece-8-compressed-$backend" 120 solve --scene five-piece --refine 8 \
        --operator compressed --backend "$backend"
done
echo "reports in $out" | tee -a "$log"
