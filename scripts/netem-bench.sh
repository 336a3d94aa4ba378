#!/usr/bin/env bash
# The stream across a shaped link: the server in one network namespace, the
# client (examples/latency) in another, joined by a veth pair shaped with
# tc netem (a one-way delay of half the round trip and a rate limit, on both
# ends). Where the kernel has no netem, tbf limits the rate and
# examples/delay_relay, in the client's namespace, holds the data half the
# round trip each way (the output says which). Needs root (ip netns, tc);
# says so and exits 0 without it.
#
#   scripts/netem-bench.sh [RATE_MBIT=100] [RTT_MS=30] [WIDTH=512] [HEIGHT=512] [UPDATES=50]
#
# Runs PNG, then JPEG 85 and WebP 85 with progressive resolution, all
# acknowledging frames; prints examples/latency's lines for each.
set -euo pipefail
cd "$(dirname "$0")/.."
rate="${1:-100}" rtt="${2:-30}" width="${3:-512}" height="${4:-512}" updates="${5:-50}"

if [ "$(id -u)" != 0 ] || ! command -v ip >/dev/null || ! command -v tc >/dev/null; then
    echo "netem-bench.sh: needs root, ip and tc (iproute2): skipping" >&2
    exit 0
fi
bin=target/release/pathstream
ex=target/release/examples/latency
relay=target/release/examples/delay_relay
[ -x "$bin" ] || cargo build --release --bin pathstream
[ -x "$ex" ] || cargo build --release --example latency
[ -x "$relay" ] || cargo build --release --example delay_relay

srv=ps-srv-$$ cli=ps-cli-$$
cleanup() {
    [ -n "${server_pid:-}" ] && kill "$server_pid" 2>/dev/null || true
    [ -n "${relay_pid:-}" ] && kill "$relay_pid" 2>/dev/null || true
    ip netns del "$srv" 2>/dev/null || true
    ip netns del "$cli" 2>/dev/null || true
}
trap cleanup EXIT
ip netns add "$srv"
ip netns add "$cli"
ip link add veth-s$$ type veth peer name veth-c$$
ip link set veth-s$$ netns "$srv"
ip link set veth-c$$ netns "$cli"
ip -n "$srv" addr add 10.77.0.1/24 dev veth-s$$
ip -n "$cli" addr add 10.77.0.2/24 dev veth-c$$
for ns in "$srv" "$cli"; do ip -n "$ns" link set lo up; done
ip -n "$srv" link set veth-s$$ up
ip -n "$cli" link set veth-c$$ up
half=$((rtt / 2))
shaped="${rate} Mbit/s, ${rtt} ms round trip (netem)"
netem=yes
for end in "$srv veth-s$$" "$cli veth-c$$"; do
    set -- $end
    # netem: delay and rate (a queue deep enough for a few frames). Kernels
    # without sch_netem (some containers) get tbf: the rate only.
    if ! ip netns exec "$1" tc qdisc add dev "$2" root netem delay "${half}ms" rate "${rate}mbit" limit 10000 2>/dev/null; then
        ip netns exec "$1" tc qdisc add dev "$2" root tbf rate "${rate}mbit" burst 64kb latency 200ms
        shaped="${rate} Mbit/s (tbf), ${rtt} ms round trip (delay_relay: this kernel has no netem)"
        netem=no
    fi
done

# Waits (5 s at most) until HOST/PORT accepts connections from the client's namespace.
reachable() {
    for _ in $(seq 50); do
        ip netns exec "$cli" bash -c "exec 3<>/dev/tcp/$1" 2>/dev/null && return
        sleep 0.1
    done
}
ip netns exec "$srv" "$bin" serve --addr 10.77.0.1:8080 --backend cpu >/dev/null 2>&1 &
server_pid=$!
reachable 10.77.0.1/8080
url=http://10.77.0.1:8080
if [ "$netem" = no ] && [ "$half" -gt 0 ]; then
    ip netns exec "$cli" "$relay" 127.0.0.1:9090 10.77.0.1:8080 "$half" >/dev/null &
    relay_pid=$!
    reachable 127.0.0.1/9090
    url=http://127.0.0.1:9090
fi
echo "link: ${shaped}; ${width}x${height}, ${updates} updates"
for stream in "format=png" "format=jpeg&quality=85&progressive=true" "format=webp&quality=85&progressive=true"; do
    echo "-- $stream"
    ip netns exec "$cli" "$ex" --url "$url" --size "$width" --height "$height" \
        --updates "$updates" --stream "$stream" --ack --fov-updates | grep -v '^session\|^PNG encode'
done
