#!/usr/bin/env bash
# The browser client's tests in a real browser: Debian's Chromium driven by
# playwright-core (no browser download) against a real `pathstream serve`.
# Installs what is missing (Node 20+ from PyPI, chromium with apt-get, the
# npm packages with `npm ci`), then runs `node --test tests/browser/`.
#
# Environment: PATHSTREAM_BIN (default target/release/pathstream; built when
# missing), CHROMIUM (default /usr/bin/chromium). Screenshot: target/browser/page.png.
set -euo pipefail
cd "$(dirname "$0")/.."

CHROMIUM="${CHROMIUM:-/usr/bin/chromium}"
export CHROMIUM
export PATHSTREAM_BIN="${PATHSTREAM_BIN:-$PWD/target/release/pathstream}"

# Node 20+ (from PyPI when the machine has none, see node-env.sh).
. scripts/node-env.sh
ensure_node

# Open Image Denoise for the servers the denoising test starts (see
# oidn-env.sh; test.sh has already exported it).
. scripts/oidn-env.sh
ensure_oidn

if [ ! -x "$CHROMIUM" ]; then
    echo "browser-tests.sh: installing chromium (apt-get)" >&2
    sudo=""
    if [ "$(id -u)" != 0 ]; then sudo="sudo"; fi
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq chromium >/dev/null
fi

# npm ci when playwright-core is missing or not the pinned version.
want="$(node -p 'require("./tests/browser/package.json").devDependencies["playwright-core"]')"
have="$(node -p 'try { require("./tests/browser/node_modules/playwright-core/package.json").version } catch { "" }')"
if [ "$want" != "$have" ]; then
    echo "browser-tests.sh: npm ci in tests/browser (playwright-core $want)" >&2
    (cd tests/browser && npm ci --no-audit --no-fund --loglevel=error)
fi

if [ ! -x "$PATHSTREAM_BIN" ]; then
    echo "browser-tests.sh: no server at $PATHSTREAM_BIN; building it" >&2
    cargo build --release --locked --bin pathstream
fi

# The files by name: Node 21+ reads a directory argument as a file.
exec node --test --test-concurrency=1 tests/browser/*.test.mjs
