#!/usr/bin/env bash
# Runs a station project as one process per node, each in a Linux network namespace of its
# own with its own address, as if every node were a host (docs/DEPLOYMENT.md). The hosts
# file (`stanice run --hosts`) says where each node is; this script builds that network:
#
#   PREFIX-net       one namespace holding a bridge per /24 subnet of the hosts file and
#                    routing between them (address .1 on each, IP forwarding on)
#   PREFIX-NODE      one per node of [nodes] (NODE with characters other than letters,
#                    digits, _ and - made _): a veth `eth0` on its subnet's bridge, its
#                    address/24, a default route via .1, loopback up
#   PREFIX-dispatch  a controlling station's namespace on the first node's subnet, at .250
#                    (STN_DISPATCH_ADDRESS to change it)
#
# Nothing of the root namespace is touched: every interface is created inside a namespace.
# Needs root (or CAP_NET_ADMIN and CAP_SYS_ADMIN) and iproute2's `ip`.
#
# Usage:
#   netns-station.sh check                 exit 0 when namespaces can be made here
#   netns-station.sh up HOSTS_FILE         the namespaces, bridges, router and addresses
#   netns-station.sh start NODE            `stanice run PROJECT --node NODE --hosts HOSTS_FILE
#                                          --store sqlite:DIR/NODE.sqlite` in NODE's namespace,
#                                          in the background (DIR/NODE.pid, DIR/NODE.log)
#   netns-station.sh start-all             every node of the hosts file
#   netns-station.sh console NODE LINE     a line to NODE's console (a fault, `status` ...);
#                                          its answer lands in DIR/NODE.log
#   netns-station.sh kill NODE             kill -9 (a crash); waits until it is gone
#   netns-station.sh stop NODE             SIGTERM (a clean stop); waits until it is gone
#   netns-station.sh exec NAME CMD [ARG..] runs CMD in the namespace of NAME (a node or
#                                          `dispatch`), in the foreground
#   netns-station.sh address NAME          NAME's address (a node or `dispatch`)
#   netns-station.sh status                namespaces and node processes
#   netns-station.sh down                  every process in the namespaces ended, every
#                                          namespace removed; also after a crash, and when
#                                          nothing is up
#
# Environment (read by every command; `up` records the project, binary and hosts file):
#   STN_PREFIX   namespace prefix (default stn); runs with different prefixes coexist
#   STN_DIR      state folder: pid files, logs, stores, console pipes
#                (default /tmp/netns-station-PREFIX)
#   STN_PROJECT  the project folder (default examples/vsetin of this repository)
#   STANICE      the stanice binary (default: `stanice` on PATH, else target/debug/stanice)
#   STN_RUN_ARGS more arguments for `stanice run` (default `--log warn`)
#
# A node's console is a named pipe (DIR/NODE.console) the process holds open for reading
# and writing: it never sees the end of its input, and `console` writes lines into it.
# Every wait is bounded (kill/stop: 10 s; console: 5 s).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PREFIX="${STN_PREFIX:-stn}"
DIR="${STN_DIR:-/tmp/netns-station-$PREFIX}"
SETTINGS="$DIR/settings"

die() { echo "netns-station: $*" >&2; exit 1; }

[[ "$PREFIX" =~ ^[A-Za-z0-9_-]{1,24}$ ]] || die "STN_PREFIX '$PREFIX': letters, digits, _ and -, at most 24"

# The namespace of a node (or `net`, `dispatch`).
ns_of() { printf '%s-%s' "$PREFIX" "$(printf '%s' "$1" | tr -c 'A-Za-z0-9_-' '_')"; }

# "NAME ADDRESS" for each entry of the hosts file's [nodes] table (written `name = "ip"`,
# the name bare or quoted; comments after `#`).
hosts_nodes() {
    awk '
        { line = $0; sub(/#.*/, "", line) }
        line ~ /^[[:space:]]*\[/ { section = line; gsub(/[][[:space:]]/, "", section); next }
        section == "nodes" && line ~ /=/ {
            split(line, kv, "=")
            key = kv[1]; value = kv[2]
            gsub(/^[[:space:]"]+|[[:space:]"]+$/, "", key)
            gsub(/^[[:space:]"]+|[[:space:]"]+$/, "", value)
            if (key != "" && value != "") print key, value
        }' "$1"
}

load_settings() {
    [ -f "$SETTINGS" ] || die "not up (no $SETTINGS): run \`$0 up HOSTS_FILE\` first"
    # shellcheck disable=SC1090
    . "$SETTINGS"
}

# The address of NAME (a node of the hosts file, or dispatch).
address_of() {
    if [ "$1" = dispatch ]; then
        printf '%s\n' "$DISPATCH_ADDRESS"
        return
    fi
    hosts_nodes "$HOSTS" | awk -v node="$1" '$1 == node { print $2; found = 1 } END { exit !found }' \
        || die "no node '$1' in $HOSTS"
}

subnet_of() { printf '%s\n' "${1%.*}"; }

pid_alive() { [ -n "$1" ] && kill -0 "$1" 2>/dev/null; }

# Waits up to $2 tenths of a second for process $1 to end.
wait_gone() {
    local pid="$1" tenths="$2"
    for _ in $(seq "$tenths"); do
        pid_alive "$pid" || return 0
        # A killed child of ours stays a zombie until reaped: not alive for us.
        if [ -r "/proc/$pid/stat" ] && [ "$(awk '{print $3}' "/proc/$pid/stat" 2>/dev/null)" = Z ]; then
            return 0
        fi
        sleep 0.1
    done
    return 1
}

cmd_check() {
    command -v ip >/dev/null || die "no \`ip\` (Debian package iproute2)"
    local probe
    probe="$(ns_of check-$$)"
    ip netns add "$probe" 2>/dev/null || die "cannot make a network namespace here (root or CAP_SYS_ADMIN needed)"
    ip -n "$probe" link add "${PREFIX:0:6}br" type bridge 2>/dev/null || { ip netns del "$probe"; die "cannot make a bridge in a namespace"; }
    ip netns del "$probe"
}

cmd_up() {
    local hosts="${1:-}"
    [ -n "$hosts" ] && [ -f "$hosts" ] || die "usage: $0 up HOSTS_FILE"
    hosts="$(cd "$(dirname "$hosts")" && pwd)/$(basename "$hosts")"
    local nodes
    nodes="$(hosts_nodes "$hosts")"
    [ -n "$nodes" ] || die "$hosts has no [nodes]"
    local project="${STN_PROJECT:-$ROOT/examples/vsetin}"
    local stanice="${STANICE:-}"
    if [ -z "$stanice" ]; then
        stanice="$(command -v stanice || true)"
        [ -n "$stanice" ] || stanice="$ROOT/target/debug/stanice"
    fi
    local first
    first="$(printf '%s\n' "$nodes" | awk 'NR == 1 { print $2 }')"
    local dispatch="${STN_DISPATCH_ADDRESS:-$(subnet_of "$first").250}"
    mkdir -p "$DIR"
    {
        printf 'HOSTS=%q\n' "$hosts"
        printf 'PROJECT=%q\n' "$project"
        printf 'STANICE=%q\n' "$stanice"
        printf 'DISPATCH_ADDRESS=%q\n' "$dispatch"
    } >"$SETTINGS"
    load_settings

    local router
    router="$(ns_of net)"
    ip netns add "$router"
    ip -n "$router" link set lo up
    ip netns exec "$router" sh -c 'echo 1 > /proc/sys/net/ipv4/ip_forward'
    # One bridge per subnet, the router at .1 on it.
    local subnets
    subnets="$( { printf '%s\n' "$nodes" | awk '{ print $2 }'; echo "$dispatch"; } | sed 's/\.[0-9]*$//' | sort -u)"
    local index=0 subnet
    declare -A bridge
    for subnet in $subnets; do
        bridge[$subnet]="br$index"
        ip -n "$router" link add "br$index" type bridge
        ip -n "$router" addr add "$subnet.1/24" dev "br$index"
        ip -n "$router" link set "br$index" up
        index=$((index + 1))
    done
    # A namespace per node (and dispatch), its veth's other end on its subnet's bridge.
    local veth=0 name address ns
    while read -r name address; do
        ns="$(ns_of "$name")"
        ip netns add "$ns"
        ip -n "$ns" link set lo up
        subnet="$(subnet_of "$address")"
        ip -n "$router" link add "v$veth" type veth peer name eth0 netns "$ns"
        ip -n "$router" link set "v$veth" master "${bridge[$subnet]}" up
        ip -n "$ns" addr add "$address/24" dev eth0
        ip -n "$ns" link set eth0 up
        ip -n "$ns" route add default via "$subnet.1"
        veth=$((veth + 1))
    done < <(printf '%s\n' "$nodes"; printf 'dispatch %s\n' "$dispatch")
    echo "up: $((veth - 1)) node namespace(s) + dispatch ($dispatch), $index subnet(s) routed by $router; state in $DIR"
}

cmd_start() {
    local node="${1:-}"
    [ -n "$node" ] || die "usage: $0 start NODE"
    load_settings
    address_of "$node" >/dev/null
    local pidfile="$DIR/$node.pid" console="$DIR/$node.console"
    if [ -f "$pidfile" ] && pid_alive "$(cat "$pidfile")"; then
        die "node $node runs already (pid $(cat "$pidfile"))"
    fi
    [ -p "$console" ] || mkfifo "$console"
    # shellcheck disable=SC2086 # STN_RUN_ARGS is a list of words
    ip netns exec "$(ns_of "$node")" "$STANICE" run "$PROJECT" --node "$node" --hosts "$HOSTS" \
        --store "sqlite:$DIR/$node.sqlite" ${STN_RUN_ARGS:---log warn} \
        0<>"$console" >>"$DIR/$node.log" 2>&1 &
    echo $! >"$pidfile"
}

cmd_start_all() {
    load_settings
    local name address
    while read -r name address; do
        cmd_start "$name"
    done < <(hosts_nodes "$HOSTS")
}

cmd_signal() {
    local signal="$1" node="${2:-}"
    [ -n "$node" ] || die "usage: $0 kill|stop NODE"
    load_settings
    local pidfile="$DIR/$node.pid"
    [ -f "$pidfile" ] || die "node $node was not started"
    local pid
    pid="$(cat "$pidfile")"
    if pid_alive "$pid"; then
        kill "-$signal" "$pid" 2>/dev/null || true
        wait_gone "$pid" 100 || die "node $node (pid $pid) still runs 10 s after SIG$signal"
    fi
    rm -f "$pidfile"
}

cmd_console() {
    local node="${1:-}"
    [ -n "$node" ] && [ $# -ge 2 ] || die "usage: $0 console NODE LINE"
    shift
    load_settings
    local pidfile="$DIR/$node.pid"
    [ -f "$pidfile" ] && pid_alive "$(cat "$pidfile")" || die "node $node does not run"
    # The node holds the pipe open, so this open does not block; the time limit is for
    # a node that ended in between.
    timeout 5 sh -c 'printf "%s\n" "$1" >"$2"' _ "$*" "$DIR/$node.console" \
        || die "node $node did not take the line"
}

cmd_exec() {
    local name="${1:-}"
    [ -n "$name" ] && [ $# -ge 2 ] || die "usage: $0 exec NAME CMD [ARG...]"
    shift
    load_settings
    address_of "$name" >/dev/null
    exec ip netns exec "$(ns_of "$name")" "$@"
}

cmd_status() {
    load_settings
    echo "hosts file $HOSTS, project $PROJECT, dispatch at $DISPATCH_ADDRESS"
    local name address pid state
    while read -r name address; do
        pid="$(cat "$DIR/$name.pid" 2>/dev/null || true)"
        if pid_alive "$pid"; then state="runs (pid $pid)"; else state="not running"; fi
        printf '  %-8s %-15s %s %s\n' "$name" "$address" "$(ns_of "$name")" "$state"
    done < <(hosts_nodes "$HOSTS")
}

cmd_down() {
    local ns pids pid
    # Every namespace of this prefix, whatever `up` got to before a crash.
    for ns in $(ip netns list 2>/dev/null | awk '{ print $1 }' | grep -E "^${PREFIX}-" || true); do
        pids="$(ip netns pids "$ns" 2>/dev/null || true)"
        for pid in $pids; do kill -TERM "$pid" 2>/dev/null || true; done
        for pid in $pids; do wait_gone "$pid" 50 || kill -KILL "$pid" 2>/dev/null || true; done
        for pid in $pids; do wait_gone "$pid" 50 || echo "netns-station: pid $pid in $ns does not end" >&2; done
        ip netns del "$ns" 2>/dev/null || true
    done
    rm -f "$DIR"/*.pid "$DIR"/*.console "$SETTINGS" 2>/dev/null || true
}

command="${1:-}"
[ $# -gt 0 ] && shift
case "$command" in
    check) cmd_check ;;
    up) cmd_up "$@" ;;
    start) cmd_start "$@" ;;
    start-all) cmd_start_all ;;
    console) cmd_console "$@" ;;
    kill) cmd_signal KILL "$@" ;;
    stop) cmd_signal TERM "$@" ;;
    exec) cmd_exec "$@" ;;
    address) load_settings; address_of "${1:?usage: $0 address NAME}" ;;
    status) cmd_status ;;
    down) cmd_down ;;
    *) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; [ -z "$command" ] || exit 2 ;;
esac
