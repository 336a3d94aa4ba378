#!/usr/bin/env bash
# The OpenCL backend's checks and benchmarks on an NVIDIA GPU box, from
# binaries built elsewhere (the box needs no Rust). docs/OPENCL.md, "On an
# NVIDIA GPU", says how the bundle is made and what this found.
#
#   BUNDLE=.gpu OUT=/tmp/gpu-out BUDGET_S=420 scripts/gpu-check.sh [steps]
#
# BUNDLE holds bin/ (pathstream, latency, clinfo; stripped), lib/
# (libOpenCL.so.1: ocl-icd; only NVIDIA's platform is registered with it)
# and tests/ (the release test binaries to run). Made on the build machine:
#   cargo test --release --workspace --no-run; cargo build --release --example latency --example encode_cost
#   apt-get download ocl-icd-libopencl1 clinfo; dpkg -x each into x/
#   strip -o .gpu/bin/pathstream target/release/pathstream (and latency, encode_cost,
#     target/release/deps/NAME-HASH as .gpu/tests/NAME); cp clinfo, libOpenCL.so.1
#   tar -cJf .gpub/bundle.tar.xz .gpu    (64 MiB travel to the device: pack it)
# The device tool sends the working tree, so .gpub/ travels and this script
# unpacks it where .gpu/ is missing. Steps (default all, in this order): find,
# tests, tune, parity, throughput, latency, encode, fair, trade. A step that would start
# after BUDGET_S seconds is skipped. Full logs go to OUT; a summary is
# printed last.
set -u
BUNDLE=$(realpath "${BUNDLE:-.gpu}")
OUT=${OUT:-/tmp/gpu-out}
BUDGET_S=${BUDGET_S:-420}
STEPS=${*:-find tests tune parity throughput latency encode fair trade}
mkdir -p "$OUT"
t0=$(date +%s)
# The bundle may travel packed (.gpub/bundle.tar.xz, made by `tar -cJf`).
if [ ! -d "$BUNDLE" ] && [ -f .gpub/bundle.tar.xz ]; then
    tar -xJf .gpub/bundle.tar.xz
fi
elapsed() { echo $(($(date +%s) - t0)); }
SUMMARY="$OUT/summary.txt"
: >"$SUMMARY"
note() { echo "$*" | tee -a "$SUMMARY"; }
P="$BUNDLE/bin/pathstream"

# NVIDIA's OpenCL: the driver's library, registered with an ICD loader.
find_opencl() {
    local lib
    for d in /usr/local/nvidia/lib64 /usr/local/nvidia/lib /usr/lib/x86_64-linux-gnu /usr/lib64 /usr/lib; do
        [ -e "$d/libnvidia-opencl.so.1" ] && lib="$d/libnvidia-opencl.so.1" && break
    done
    if [ -z "${lib:-}" ]; then
        lib=$(timeout 20 find / -path /proc -prune -o -path /sys -prune -o -name 'libnvidia-opencl.so*' -print 2>/dev/null | head -1)
    fi
    note "nvidia opencl library: ${lib:-none found}"
    note "system vendors: $(ls /etc/OpenCL/vendors 2>/dev/null | tr '\n' ' ')"
    note "system loader: $(ldconfig -p | grep -o '/.*libOpenCL.so.1' | head -1)"
    # Only NVIDIA's platform, through the bundled ocl-icd loader (it reads
    # OCL_ICD_VENDORS; CUDA's own loader also read /etc/OpenCL/vendors, whose
    # PoCL then came first as device 0).
    if [ -n "${lib:-}" ]; then
        mkdir -p /tmp/icd && echo "$lib" >/tmp/icd/nvidia.icd
        export OCL_ICD_VENDORS=/tmp/icd
        export LD_LIBRARY_PATH="$BUNDLE/lib:${LD_LIBRARY_PATH:-}"
        export OPENCL_DYLIB_PATH="$BUNDLE/lib/libOpenCL.so.1"
        note "OCL_ICD_VENDORS=/tmp/icd (nvidia.icd -> $lib), loader $OPENCL_DYLIB_PATH"
    fi
}

step_find() {
    nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv,noheader | tee -a "$SUMMARY"
    "$BUNDLE/bin/clinfo" >"$OUT/clinfo.txt" 2>&1
    grep -E "Platform Name|Device Name|Driver Version|Max compute units|Device Version" "$OUT/clinfo.txt" | head -8
    "$P" devices 2>&1 | tee -a "$SUMMARY"
    if ! "$P" devices 2>&1 | grep -q '\[0\] NVIDIA'; then
        note "device 0 is not NVIDIA's: stopping"
        exit 3
    fi
}

step_tests() {
    # Tests find their fixtures under the build machine's paths.
    [ -e /work/main ] || { mkdir -p /work && ln -s "$PWD" /work/main; }
    mkdir -p target/release && cp "$P" target/release/pathstream
    for t in "$BUNDLE"/tests/*; do
        local name rc
        name=$(basename "$t")
        [ "$(elapsed)" -gt "$BUDGET_S" ] && { note "test $name: skipped (budget)"; continue; }
        CI=true timeout 150 "$t" --test-threads 16 >"$OUT/test-$name.log" 2>&1
        rc=$?
        note "test $name: rc $rc, $(grep -E '^test result' "$OUT/test-$name.log" | tail -1) ($(elapsed) s)"
        [ $rc -ne 0 ] && grep -E "^test .* FAILED|panicked|error" "$OUT/test-$name.log" | head -8 | tee -a "$SUMMARY"
    done
}

# cornell-glass at 1920x1080 (depth 6, NEE on): the launch shapes.
bench_glass() {
    "$P" bench --backend opencl --sections throughput --scenes cornell-glass \
        --throughput-seconds 2 2>&1 | grep -E "1920x1080" | head -1
}
step_tune() {
    RUST_LOG=pathstream=info PATHSTREAM_OPENCL_OPTIONS=-cl-nv-verbose "$P" bench --backend opencl \
        --sections throughput --scenes cornell-glass,cornell-mesh-pbr --throughput-seconds 0.5 >"$OUT/nv-verbose.log" 2>&1
    grep -iE "registers|spill|stack|lmem|smem" "$OUT/nv-verbose.log" | sort | uniq -c | head -12 | tee -a "$SUMMARY"
    note "glass 1080p default: $(bench_glass)"
    note "glass 1080p launch 65536 px: $(PATHSTREAM_OPENCL_LAUNCH_PIXELS=65536 bench_glass)"
    for l in 128 256; do
        note "glass 1080p local $l: $(PATHSTREAM_OPENCL_LOCAL_SIZE=$l bench_glass)"
    done
}

# Bit-for-bit parity with the CPU (the routine checks), under extra build
# options if PARITY_OPTIONS lists them ('' is the default build). OpenCL's
# dot, cross and normalize are fused on NVIDIA; the kernel uses its own.
step_parity() {
    for o in ${PARITY_OPTIONS:-""}; do
        for t in opencl_parity opencl_parity_meshes; do
            PATHSTREAM_OPENCL_OPTIONS="$o" CI=true timeout 90 "$BUNDLE/tests/$t" --test-threads 16 >"$OUT/parity-$t.log" 2>&1
            note "parity '$o' $t: $(grep -E '^test result' "$OUT/parity-$t.log" | cut -c1-40)"
            grep -E "^test .* FAILED" "$OUT/parity-$t.log" | head -6 | tee -a "$SUMMARY"
        done
    done
    note "  glass 1080p: $(bench_glass)"
}

step_throughput() {
    "$P" bench --backend opencl --sections throughput,specialisation --throughput-seconds 1.5 --out "$OUT/bench" >"$OUT/throughput.txt" 2>&1
    grep -E "^\| opencl|specialised|generic" "$OUT/throughput.txt" | tee -a "$SUMMARY"
}

# Update-to-frame latency at 1080p, and where a pass's time goes (debug
# logs: the OpenCL render's stages, the pass, the frame's encoding).
step_latency() {
    local i=0 s pinned
    # stream query, then PATHSTREAM_OPENCL_PINNED (0: pageable read-back).
    for run in ${LATENCY_RUNS:-":1" "format=jpeg&quality=85:1" ":0"}; do
        s=${run%:*} pinned=${run##*:}
        note "latency 1920x1080 stream '$s', pinned read-back $pinned:"
        PATHSTREAM_OPENCL_PINNED=$pinned RUST_LOG=pathstream=debug,pathstream::api::ws=trace NO_COLOR=1 timeout 150 "$BUNDLE/bin/latency" \
            --backend opencl --size 1920 --height 1080 --updates 40 ${s:+--stream "$s"} --ack --fov-updates >"$OUT/latency-$i.log" 2>&1
        grep -E "update ->|frames delivered|encode at" "$OUT/latency-$i.log" | tee -a "$SUMMARY"
        python3 - "$OUT/latency-$i.log" <<'PY' | tee -a "$SUMMARY"
import re, statistics, sys
fields = ["ready_ms", "launch_ms", "read_back_ms", "image_ms", "encode_ms", "ms"]
seen = {f: [] for f in fields}
for line in open(sys.argv[1], errors="replace"):
    line = re.sub(r"\x1b\[[0-9;]*m", "", line)
    for f in fields:
        if f == "ms" and "pass ends" not in line:
            continue
        m = re.search(r"(?<![a-z_])" + f + r"=([0-9.]+)", line)
        if m:
            seen[f].append(float(m.group(1)))
for f, v in seen.items():
    if v:
        v.sort()
        print(f"  {'pass_ms' if f == 'ms' else f}: n {len(v)}, median {statistics.median(v):.2f}, p95 {v[int(0.95 * (len(v) - 1))]:.2f}")
PY
        i=$((i + 1))
    done
}

step_glass() {
    note "glass 1080p: $(bench_glass)"
}

# Frame encodings at 1080p on the box's cores.
step_encode() {
    "$BUNDLE/bin/encode_cost" cornell-glass 1920 1080 1 2>&1 | grep -E "PNG|JPEG" | tee -a "$SUMMARY"
}

# Four 1080p sessions on one GPU: samples each after 10 s.
step_fair() {
    "$P" serve --backend opencl --addr 127.0.0.1:8931 >"$OUT/serve.log" 2>&1 &
    local pid=$! ids=()
    sleep 2
    for i in 1 2 3 4; do
        ids+=("$(curl -s -X POST localhost:8931/api/sessions -H 'content-type: application/json' \
            -d "{\"scene\":\"cornell-glass\",\"width\":1920,\"height\":1080,\"quality\":{\"seed\":$i}}" |
            python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])')")
    done
    sleep 10
    for id in "${ids[@]}"; do
        note "session $id: $(curl -s "localhost:8931/api/sessions/$id" | python3 -c 'import json,sys; d=json.load(sys.stdin); print({k: d.get(k) for k in ("spp", "state", "backend", "error")})')"
    done
    kill $pid
}

step_trade() {
    timeout 170 "$P" bench --backend opencl --sections trade,calibration --trade-seconds 2 --trade-size 256x256 --out "$OUT/trade" >"$OUT/trade.txt" 2>&1
    tail -40 "$OUT/trade.txt" | tee -a "$SUMMARY" >/dev/null
    note "trade: rc $?, $(wc -l <"$OUT/trade.txt") lines (trade.txt)"
}

find_opencl
for s in $STEPS; do
    if [ "$(elapsed)" -gt "$BUDGET_S" ]; then
        note "== $s: skipped ($(elapsed) s > budget)"
        continue
    fi
    note "== $s ($(elapsed) s)"
    "step_$s"
done
note "== done ($(elapsed) s)"
# Everything in one archive (a caller may fetch only a few files).
(cd "$OUT" && tar -czf ../gpu-logs.tgz . && mv ../gpu-logs.tgz .)
echo
echo "######## summary"
cat "$SUMMARY"
