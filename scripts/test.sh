#!/usr/bin/env bash
# The whole test suite: installs what the tests need when it is missing,
# then runs every test in release mode (renders are heavy; debug is 30x slower).
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v cargo >/dev/null 2>&1; then
    echo "error: cargo not found; install Rust from https://rustup.rs" >&2
    exit 1
fi

# Nothing beyond Rust is needed yet. (The OpenCL and browser suites will
# install ocl-icd-libopencl1, pocl-opencl-icd and chromium here.)

cargo test --release --workspace --locked "$@"
