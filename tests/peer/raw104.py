#!/usr/bin/env python3
"""Raw-socket IEC 60870-5-104 helpers for tests (standard library only).

  raw104.py send --port P [--host 127.0.0.1] [--startdt] --hex HEX [--hex HEX ...]
            [--wait SECS]
      Connect, optionally do STARTDT act/con, send each HEX chunk as its own
      TCP segment (e.g. a deliberately broken frame), print what comes back
      for --wait seconds, close. One JSON line per event.

  raw104.py gi-server --port P [--host 127.0.0.1] [--ca 1] --points N
            [--type M_ME_NC_1|M_SP_NA_1] [--base 10000] [--k 12] [--w 8]
            [--max-seconds 600] [--connections 1]
      A minimal outstation that answers a station interrogation with N
      points packed in sequence ASDUs (SQ=1), honouring the k window
      (waits for acknowledgements, like a real outstation). It exists to
      feed the c104 client a GI bigger than c104's own server can send
      (c104's GI answer is capped by a 100-message queue). STARTDT, TESTFR
      and STOPDT are answered; other I frames are acknowledged and ignored.

Only loopback addresses are used by the tests. All loops are bounded.
"""

import argparse
import json
import select
import socket
import struct
import sys
import time


def emit(obj):
    sys.stdout.write(json.dumps(obj, separators=(",", ":")) + "\n")
    sys.stdout.flush()


U_NAMES = {0x07: "STARTDT_ACT", 0x0B: "STARTDT_CON", 0x13: "STOPDT_ACT",
           0x23: "STOPDT_CON", 0x43: "TESTFR_ACT", 0x83: "TESTFR_CON"}


class Framer:
    """Splits a byte stream into APDUs (start 0x68, length octet)."""

    def __init__(self):
        self.buf = b""

    def feed(self, data):
        self.buf += data
        out = []
        while len(self.buf) >= 2:
            if self.buf[0] != 0x68:
                raise ValueError("bad start octet 0x%02x" % self.buf[0])
            n = self.buf[1]
            if len(self.buf) < 2 + n:
                break
            out.append(self.buf[:2 + n])
            self.buf = self.buf[2 + n:]
        return out


def u_frame(code):
    return bytes([0x68, 0x04, code, 0, 0, 0])


def s_frame(nr):
    return bytes([0x68, 0x04, 0x01, 0x00]) + struct.pack("<H", (nr << 1) & 0xFFFF)


def i_frame(ns, nr, asdu):
    return bytes([0x68, 4 + len(asdu)]) + struct.pack("<HH", (ns << 1) & 0xFFFF,
                                                      (nr << 1) & 0xFFFF) + asdu


# ------------------------------------------------------------------ send
def cmd_send(a):
    chunks = []
    for h in a.hex:
        try:
            chunks.append(bytes.fromhex(h.replace(" ", "")))
        except ValueError:
            raise SystemExit("bad --hex %r" % h)
    s = socket.create_connection((a.host, a.port), timeout=a.connect_timeout)
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    emit({"event": "connected", "host": a.host, "port": a.port})
    fr = Framer()
    if a.startdt:
        s.sendall(u_frame(0x07))
        deadline = time.monotonic() + 5
        got = False
        while time.monotonic() < deadline and not got:
            r, _, _ = select.select([s], [], [], 0.1)
            if r:
                data = s.recv(4096)
                if not data:
                    break
                for apdu in fr.feed(data):
                    emit({"event": "rx", "hex": apdu.hex()})
                    if len(apdu) >= 3 and apdu[2] == 0x0B:
                        got = True
        emit({"event": "startdt", "confirmed": got})
    for c in chunks:
        s.sendall(c)
        emit({"event": "sent", "hex": c.hex()})
        time.sleep(0.05)  # separate TCP segments
    deadline = time.monotonic() + a.wait
    closed = False
    raw_left = b""
    while time.monotonic() < deadline:
        r, _, _ = select.select([s], [], [], 0.05)
        if not r:
            continue
        try:
            data = s.recv(4096)
        except OSError as e:
            emit({"event": "error", "message": str(e)})
            closed = True
            break
        if not data:
            closed = True
            break
        try:
            for apdu in fr.feed(data):
                emit({"event": "rx", "hex": apdu.hex()})
        except ValueError:
            raw_left += data
    if raw_left:
        emit({"event": "rx_unframed", "hex": raw_left.hex()})
    emit({"event": "done", "peer_closed": closed})
    s.close()
    return 0


# ------------------------------------------------------------------ gi-server
def gi_asdus(ca, n_points, typ, base):
    """Yield ASDUs (bytes) answering a station GI with n_points in sequence."""
    if typ == "M_ME_NC_1":
        tid, per = 13, 48   # 5 octets per object: float + QDS
    else:
        tid, per = 1, 127   # 1 octet per object: SIQ
    i = 0
    while i < n_points:
        n = min(per, n_points - i)
        ioa = base + i
        head = bytes([tid, 0x80 | n, 20, 0]) + struct.pack("<H", ca) + \
            struct.pack("<I", ioa)[:3]
        if tid == 13:
            body = b"".join(struct.pack("<fB", float(i + j), 0) for j in range(n))
        else:
            body = bytes([(i + j) & 1 for j in range(n)])
        yield head + body
        i += n


def serve_connection(conn, a):
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    fr = Framer()
    ns = nr = 0          # our send counter, our receive counter
    acked = 0            # peer's last N(R)
    started = False
    outq = []            # ASDUs waiting for the window
    gi_active = False
    gen = None
    unacked_rx = 0
    t_end = time.monotonic() + a.max_seconds
    gi_t0 = None

    def send_i(asdu):
        nonlocal ns, unacked_rx
        conn.sendall(i_frame(ns, nr, asdu))
        ns = (ns + 1) % 32768
        unacked_rx = 0

    while time.monotonic() < t_end:
        # fill the window
        while started and (ns - acked) % 32768 < a.k:
            if outq:
                send_i(outq.pop(0))
                continue
            if gen is not None:
                nxt = next(gen, None)
                if nxt is None:
                    gen = None
                    continue
                send_i(nxt)
                continue
            if gi_active:
                gi_active = False
                send_i(bytes([100, 1, 10, 0]) + struct.pack("<H", a.ca) + b"\x00\x00\x00\x14")
                emit({"event": "gi_done", "points": a.points,
                      "seconds": round(time.monotonic() - gi_t0, 6)})
                continue
            break
        window_full = started and ((ns - acked) % 32768 >= a.k)
        r, _, _ = select.select([conn], [], [], 0.5 if not window_full else 0.05)
        if not r:
            if unacked_rx:
                conn.sendall(s_frame(nr))
                unacked_rx = 0
            continue
        data = conn.recv(65536)
        if not data:
            return
        for apdu in fr.feed(data):
            c1 = apdu[2]
            if c1 & 0x01 == 0:       # I
                peer_nr = struct.unpack("<H", apdu[4:6])[0] >> 1
                acked = peer_nr
                nr = (nr + 1) % 32768
                unacked_rx += 1
                tid = apdu[6] if len(apdu) > 6 else None
                if tid == 100:
                    qoi = apdu[15] if len(apdu) > 15 else 20
                    con = bytearray(apdu[6:])
                    con[2] = (con[2] & 0xC0) | 7
                    outq.append(bytes(con))
                    emit({"event": "interrogation", "qoi": qoi})
                    if qoi == 20:
                        gen = gi_asdus(a.ca, a.points, a.type, a.base)
                        gi_active = True
                        gi_t0 = time.monotonic()
                if unacked_rx >= a.w:
                    conn.sendall(s_frame(nr))
                    unacked_rx = 0
            elif c1 & 0x03 == 0x01:  # S
                acked = struct.unpack("<H", apdu[4:6])[0] >> 1
            else:                    # U
                name = U_NAMES.get(c1, hex(c1))
                emit({"event": "u_frame", "u": name})
                if c1 == 0x07:
                    started = True
                    conn.sendall(u_frame(0x0B))
                elif c1 == 0x13:
                    started = False
                    conn.sendall(u_frame(0x23))
                elif c1 == 0x43:
                    conn.sendall(u_frame(0x83))


def cmd_gi_server(a):
    srv = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    srv.bind((a.host, a.port))
    srv.listen(1)
    srv.settimeout(1.0)
    emit({"event": "ready", "host": a.host, "port": a.port, "points": a.points,
          "type": a.type})
    t_end = time.monotonic() + a.max_seconds
    served = 0
    while served < a.connections and time.monotonic() < t_end:
        try:
            conn, peer = srv.accept()
        except socket.timeout:
            continue
        emit({"event": "connected", "peer": peer[0]})
        try:
            serve_connection(conn, a)
        except (OSError, ValueError) as e:
            emit({"event": "error", "message": str(e)})
        finally:
            conn.close()
        emit({"event": "disconnected"})
        served += 1
    srv.close()
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("send")
    s.add_argument("--host", default="127.0.0.1")
    s.add_argument("--port", type=int, required=True)
    s.add_argument("--startdt", action="store_true")
    s.add_argument("--hex", action="append", required=True)
    s.add_argument("--wait", type=float, default=1.0)
    s.add_argument("--connect-timeout", type=float, default=5.0)
    g = sub.add_parser("gi-server")
    g.add_argument("--host", default="127.0.0.1")
    g.add_argument("--port", type=int, required=True)
    g.add_argument("--ca", type=int, default=1)
    g.add_argument("--points", type=int, required=True)
    g.add_argument("--type", choices=["M_ME_NC_1", "M_SP_NA_1"], default="M_ME_NC_1")
    g.add_argument("--base", type=int, default=10000)
    g.add_argument("--k", type=int, default=12)
    g.add_argument("--w", type=int, default=8)
    g.add_argument("--max-seconds", type=float, default=600.0)
    g.add_argument("--connections", type=int, default=1)
    a = ap.parse_args(argv)
    return cmd_send(a) if a.cmd == "send" else cmd_gi_server(a)


if __name__ == "__main__":
    sys.exit(main())
