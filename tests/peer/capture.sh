#!/usr/bin/env bash
# Capture loopback IEC 104 traffic with tshark.
#
#   capture.sh start PORT FILE   start `tshark -i lo -f "tcp port PORT" -w FILE`
#                                in the background; returns once tshark is
#                                capturing (FILE has its pcapng header and
#                                tshark said "Capturing on"), at most 15 s.
#                                The tshark pid is kept in FILE.pid.
#   capture.sh stop FILE         stop that tshark (SIGINT, so it flushes),
#                                wait for it (at most 10 s, then SIGKILL),
#                                print the number of captured frames.
#
# Needs root (or capture rights) and tshark (scripts/install-test-deps.sh).
# Only the loopback interface is used.
set -euo pipefail

usage() {
    echo "usage: $0 start PORT FILE | stop FILE" >&2
    exit 2
}

cmd="${1:-}"
case "$cmd" in
start)
    [ $# -eq 3 ] || usage
    port="$2"; file="$3"
    case "$port" in ''|*[!0-9]*) echo "capture.sh: bad port '$port'" >&2; exit 2;; esac
    pidfile="$file.pid"; errfile="$file.stderr"
    if [ -f "$pidfile" ] && kill -0 "$(cat "$pidfile")" 2>/dev/null; then
        echo "capture.sh: a capture into $file is already running (pid $(cat "$pidfile"))" >&2
        exit 1
    fi
    rm -f "$file" "$errfile"
    mkdir -p "$(dirname "$file")"
    # -q: no packet count on the terminal; -n: no name resolution.
    # setsid: own session, so a Ctrl-C / SIGINT to our caller's process
    # group does not hit it; we stop it by pid.
    setsid tshark -n -q -i lo -f "tcp port $port" -w "$file" </dev/null >/dev/null 2>"$errfile" &
    pid=$!
    echo "$pid" >"$pidfile"
    for _ in $(seq 1 150); do            # 150 x 0.1 s = 15 s at most
        if ! kill -0 "$pid" 2>/dev/null; then
            echo "capture.sh: tshark exited early:" >&2
            cat "$errfile" >&2 || true
            rm -f "$pidfile"
            exit 1
        fi
        # pcapng header (SHB + IDB) is at least 28 + 20 bytes
        if grep -q "Capturing on" "$errfile" 2>/dev/null \
            && [ -s "$file" ] && [ "$(stat -c %s "$file")" -ge 48 ]; then
            # libpcap may still be attaching its BPF filter; a short grace
            sleep 0.2
            echo "capture.sh: capturing tcp port $port on lo into $file (pid $pid)"
            exit 0
        fi
        sleep 0.1
    done
    echo "capture.sh: tshark did not start capturing within 15 s:" >&2
    cat "$errfile" >&2 || true
    kill "$pid" 2>/dev/null || true
    rm -f "$pidfile"
    exit 1
    ;;
stop)
    [ $# -eq 2 ] || usage
    file="$2"; pidfile="$file.pid"
    if [ ! -f "$pidfile" ]; then
        echo "capture.sh: no capture running for $file (no $pidfile)" >&2
        exit 1
    fi
    pid="$(cat "$pidfile")"
    # give dumpcap a moment to read the last packets out of the socket buffer
    sleep 0.3
    if kill -0 "$pid" 2>/dev/null; then
        kill -INT "$pid" 2>/dev/null || true
        for _ in $(seq 1 100); do        # 10 s at most
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.1
        done
        if kill -0 "$pid" 2>/dev/null; then
            echo "capture.sh: tshark $pid ignored SIGINT, killing it" >&2
            kill -KILL "$pid" 2>/dev/null || true
        fi
    fi
    rm -f "$pidfile"
    if [ ! -s "$file" ]; then
        echo "capture.sh: $file is empty or missing" >&2
        exit 1
    fi
    frames="$(tshark -n -r "$file" -T fields -e frame.number 2>/dev/null | wc -l)"
    echo "capture.sh: stopped (pid $pid), $frames frames in $file"
    ;;
*)
    usage
    ;;
esac
