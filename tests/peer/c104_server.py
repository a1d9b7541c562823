#!/usr/bin/env python3
"""c104 (lib60870-C) IEC 60870-5-104 outstation for interoperability tests.

Prints one JSON line per notable happening on stdout (see README.md for the
exact formats) and exits cleanly on SIGTERM / SIGINT, when its stdin pipe is
closed, or after --max-seconds.

Point set (common address --ca):
  monitor    M_SP_NA_1 100..109   value = (ioa % 2 == 1)
             M_DP_NA_1 200..204   DPI 1,2,0,3,2 (OFF, ON, INTERMEDIATE, INDETERMINATE, ON)
             M_ME_NA_1 300..304   0.0, 0.25, -0.5, 0.75, -1.0
             M_ME_NB_1 400..404   0, 100, -100, 32767, -32768
             M_ME_NC_1 500..504   0.0, 1.5, -2.25, 1024.0, 0.125
             M_ST_NA_1 600        position 5, transient false
             M_BO_NA_1 700        0x12345678
             M_IT_NA_1 800        counter 123456 (not part of a station GI)
             M_SP_TB_1 150, M_ME_TF_1 550 (time tagged)
  commands   (feedback point = command IOA + 1000, same value)
             C_SC_NA_1 2021 -> M_SP_NA_1 3021   direct
             C_SC_NA_1 2022 -> M_SP_NA_1 3022   direct
             C_SC_NA_1 2023 -> M_SP_NA_1 3023   select-before-operate required
             C_SC_NA_1 2029                      always refused (negative ACT_CON)
             C_SC_TA_1 2031 -> M_SP_TB_1 3031   direct, time tagged
             C_DC_NA_1 2100 -> M_DP_NA_1 3100   direct
             C_DC_NA_1 2101 -> M_DP_NA_1 3101   select-before-operate required
             C_RC_NA_1 2500 -> M_ST_NA_1 3500   LOWER -1 / HIGHER +1 on the position
             C_SE_NC_1 2200 -> M_ME_NC_1 3200   direct
             C_SE_NA_1 2300 -> M_ME_NA_1 3300   direct
             C_SE_NB_1 2400 -> M_ME_NB_1 3400   direct
             C_BO_NA_1 2600 -> M_BO_NA_1 3600   direct
  bulk       --points N extra points of --points-type at IOA --points-base..,
             value = index (for the big GI benchmark; see README: c104's own
             GI answer is capped by its 100-message queue)
"""

import argparse
import os
import signal
import stat
import sys
import threading
import time

import c104

from peer_common import (Deadline, apply_apci, c104_version, command_select_bit,
                         decode_command_value, emit, info_extra, parse_apdu,
                         time_to_json, value_to_json)

T = c104.Type

MONITOR = []  # (ioa, type, value)
for i in range(10):
    MONITOR.append((100 + i, T.M_SP_NA_1, (100 + i) % 2 == 1))
for i, d in enumerate([c104.Double.OFF, c104.Double.ON, c104.Double.INTERMEDIATE,
                       c104.Double.INDETERMINATE, c104.Double.ON]):
    MONITOR.append((200 + i, T.M_DP_NA_1, d))
for i, v in enumerate([0.0, 0.25, -0.5, 0.75, -1.0]):
    MONITOR.append((300 + i, T.M_ME_NA_1, c104.NormalizedFloat(v)))
for i, v in enumerate([0, 100, -100, 32767, -32768]):
    MONITOR.append((400 + i, T.M_ME_NB_1, c104.Int16(v)))
SPONT_FLOAT_IOAS = [500, 501, 502, 503, 504]
for i, v in enumerate([0.0, 1.5, -2.25, 1024.0, 0.125]):
    MONITOR.append((500 + i, T.M_ME_NC_1, v))
MONITOR.append((600, T.M_ST_NA_1, c104.Int7(5)))
MONITOR.append((700, T.M_BO_NA_1, c104.Byte32((0x12345678).to_bytes(4, "little"))))
MONITOR.append((800, T.M_IT_NA_1, 123456))
MONITOR.append((150, T.M_SP_TB_1, True))
MONITOR.append((550, T.M_ME_TF_1, 2.5))

# command ioa -> (command type, feedback type or None, select-before-operate, refuse)
COMMANDS = {
    2021: (T.C_SC_NA_1, T.M_SP_NA_1, False, False),
    2022: (T.C_SC_NA_1, T.M_SP_NA_1, False, False),
    2023: (T.C_SC_NA_1, T.M_SP_NA_1, True, False),
    2029: (T.C_SC_NA_1, None, False, True),
    2031: (T.C_SC_TA_1, T.M_SP_TB_1, False, False),
    2100: (T.C_DC_NA_1, T.M_DP_NA_1, False, False),
    2101: (T.C_DC_NA_1, T.M_DP_NA_1, True, False),
    2200: (T.C_SE_NC_1, T.M_ME_NC_1, False, False),
    2300: (T.C_SE_NA_1, T.M_ME_NA_1, False, False),
    2400: (T.C_SE_NB_1, T.M_ME_NB_1, False, False),
    2500: (T.C_RC_NA_1, T.M_ST_NA_1, False, False),
    2600: (T.C_BO_NA_1, T.M_BO_NA_1, False, False),
}
FEEDBACK_OFFSET = 1000
COT_NAMES = {int(v.value): n for n, v in c104.Cot.__members__.items()}
FEEDBACK_INITIAL = {
    T.M_SP_NA_1: False, T.M_SP_TB_1: False, T.M_DP_NA_1: c104.Double.OFF,
    T.M_ME_NC_1: 0.0, T.M_ME_NA_1: c104.NormalizedFloat(0.0),
    T.M_ME_NB_1: c104.Int16(0), T.M_ST_NA_1: c104.Int7(0),
    T.M_BO_NA_1: c104.Byte32(bytes(4)),
}

BULK_TYPES = {
    "M_SP_NA_1": lambda i: bool(i % 2),
    "M_DP_NA_1": lambda i: c104.Double.ON if i % 2 else c104.Double.OFF,
    "M_ME_NA_1": lambda i: c104.NormalizedFloat((i % 1000) / 1000.0),
    "M_ME_NB_1": lambda i: c104.Int16(i % 32768),
    "M_ME_NC_1": lambda i: float(i),
}


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--host", default="127.0.0.1",
                   help="listen address (loopback only in tests)")
    p.add_argument("--port", type=int, default=2404)
    p.add_argument("--ca", type=int, default=1, help="common address (1..65534)")
    p.add_argument("--points", type=int, default=0,
                   help="number of extra bulk points for the big GI benchmark")
    p.add_argument("--points-type", default="M_ME_NC_1", choices=sorted(BULK_TYPES))
    p.add_argument("--points-base", type=int, default=10000,
                   help="IOA of the first bulk point")
    p.add_argument("--spontaneous-rate", type=float, default=0.0,
                   help="spontaneous float changes per second (0 = off)")
    p.add_argument("--spontaneous-count", type=int, default=0,
                   help="stop after this many spontaneous events (0 = until exit)")
    p.add_argument("--spontaneous-delay", type=float, default=0.5,
                   help="seconds between the first STARTDT and the first event")
    p.add_argument("--spontaneous-window", type=int, default=80,
                   help="backpressure: at most this many events handed to c104 "
                        "but not yet on the wire (c104 silently drops what "
                        "overflows its 100-message queue); 0 = no limit")
    p.add_argument("--feedback-cot", choices=["spont", "retrem"], default="spont",
                   help="cause of the feedback point after a command: "
                        "spont = SPONTANEOUS (3), sent --feedback-delay-ms after "
                        "the command was accepted; retrem = RETURN_INFO_REMOTE "
                        "(11), sent by c104 right after ACT_CON / ACT_TERM")
    p.add_argument("--feedback-delay-ms", type=int, default=20)
    p.add_argument("--select-timeout-ms", type=int, default=10000,
                   help="how long a select stays valid (c104 select_timeout_ms)")
    p.add_argument("--tick-rate-ms", type=int, default=100,
                   help="c104 server thread tick (>= 50)")
    p.add_argument("--max-seconds", type=float, default=1800.0,
                   help="exit after this many seconds whatever happens")
    p.add_argument("--stdin", choices=["auto", "watch", "ignore"], default="auto",
                   help="exit when stdin reaches EOF: auto = only if stdin is a pipe")
    p.add_argument("--raw-log", action="store_true",
                   help="emit a 'raw' line (hex + c104.explain_bytes) per frame")
    p.add_argument("--k", type=int, default=None, help="APCI k (c104 default 12)")
    p.add_argument("--w", type=int, default=None, help="APCI w (c104 default 8)")
    p.add_argument("--t1", type=int, default=None, help="APCI t1 seconds (default 15)")
    p.add_argument("--t2", type=int, default=None, help="APCI t2 seconds (default 10)")
    p.add_argument("--t3", type=int, default=None, help="APCI t3 seconds (default 20)")
    return p.parse_args(argv)


class Outstation:
    def __init__(self, args):
        self.args = args
        self.stop_event = threading.Event()
        self.stop_reason = None
        self.startdt_event = threading.Event()
        self.server = c104.Server(ip=args.host, port=args.port,
                                  tick_rate_ms=args.tick_rate_ms,
                                  select_timeout_ms=args.select_timeout_ms)
        apply_apci(self.server.protocol_parameters, args)
        self.station = self.server.add_station(common_address=args.ca)
        if self.station is None:
            raise SystemExit("cannot add station %d" % args.ca)
        self.commands_received = 0
        self.spont_sent = 0
        self.spont_failed = 0
        self._build_points()
        self.server.on_connect(callable=self._on_connect)
        self.server.on_receive_raw(callable=self._on_receive_raw)
        self.wire_spont_objects = 0
        self.server.on_send_raw(callable=self._on_send_raw)
        self.server.on_unexpected_message(callable=self._on_unexpected)

    # ------------------------------------------------------------ points
    def _add(self, ioa, typ, **kw):
        p = self.station.add_point(io_address=ioa, type=typ, **kw)
        if p is None:
            raise SystemExit("cannot add point %s at IOA %d" % (typ.name, ioa))
        return p

    def _build_points(self):
        a = self.args
        self.gi_points = 0
        for ioa, typ, val in MONITOR:
            p = self._add(ioa, typ)
            p.value = val
            if typ != T.M_IT_NA_1:
                self.gi_points += 1
        self.spont_points = [self.station.get_point(i) for i in SPONT_FLOAT_IOAS]
        self.feedback = {}
        for ioa, (ctyp, ftyp, sbo, refuse) in COMMANDS.items():
            kw = {"command_mode": c104.CommandMode.SELECT_AND_EXECUTE if sbo
                  else c104.CommandMode.DIRECT}
            fb = None
            if ftyp is not None:
                fb = self._add(ioa + FEEDBACK_OFFSET, ftyp)
                fb.value = FEEDBACK_INITIAL[ftyp]
                self.gi_points += 1
                if a.feedback_cot == "retrem":
                    kw["related_io_address"] = ioa + FEEDBACK_OFFSET
                    kw["related_io_autoreturn"] = True
            cp = self._add(ioa, ctyp, **kw)
            cp.on_receive(callable=self._on_command)
            self.feedback[ioa] = fb
        if a.points > 0:
            if a.points_base <= 3600 or a.points_base + a.points > 0xFFFFFF:
                raise SystemExit("--points-base/--points out of range (must be > 3600, <= 2^24-1)")
            mk = BULK_TYPES[a.points_type]
            typ = getattr(T, a.points_type)
            t0 = time.monotonic()
            for i in range(a.points):
                p = self._add(a.points_base + i, typ)
                p.value = mk(i)
            self.gi_points += a.points
            emit({"event": "bulk_points", "count": a.points, "type": a.points_type,
                  "first_ioa": a.points_base, "seconds": round(time.monotonic() - t0, 3)})
            # c104 builds its whole GI answer at once into lib60870's
            # outgoing queue (100 messages) + the k window (12): whatever
            # does not fit is dropped silently, ACT_TERM included (README)
            per_asdu = {"M_SP_NA_1": 60, "M_DP_NA_1": 60, "M_ME_NA_1": 40,
                        "M_ME_NB_1": 40, "M_ME_NC_1": 30}[a.points_type]
            est = 12 + (a.points + per_asdu - 1) // per_asdu
            if est > 100:
                emit({"event": "warning",
                      "message": "c104 answers a GI with at most ~100-110 ASDUs and "
                                 "drops the rest (ACT_TERM too); %d %s points need "
                                 "~%d ASDUs: use at most ~%d, or raw104.py gi-server"
                                 % (a.points, a.points_type, est, 88 * per_asdu)})

    # ------------------------------------------------------------ callbacks
    def _on_connect(self, server: c104.Server, ip: str) -> bool:
        emit({"event": "connected", "peer": ip})
        return True

    def _on_unexpected(self, server: c104.Server, message: c104.IncomingMessage,
                       cause: c104.Umc) -> None:
        try:
            emit({"event": "unexpected_message", "cause": cause.name,
                  "type": message.type.name, "ioa": message.io_address,
                  "ca": message.common_address, "cot": message.cot.name})
        except Exception as e:  # pragma: no cover - defensive
            emit({"event": "unexpected_message", "cause": str(cause), "error": str(e)})

    def _on_receive_raw(self, server: c104.Server, data: bytes) -> None:
        d = parse_apdu(data)
        if self.args.raw_log:
            emit({"event": "raw", "dir": "rx", "hex": data.hex(),
                  "explain": c104.explain_bytes(apdu=data)})
        if d is None:
            return
        if d["frame"] == "U":
            if d["u"] == "STARTDT_ACT":
                self.startdt_event.set()
            emit({"event": "u_frame", "u": d["u"]})
        elif d["frame"] == "I" and "type_id" in d:
            tid = d["type_id"]
            if tid == 100:
                qoi = data[15] if len(data) > 15 else None
                emit({"event": "interrogation", "qoi": qoi, "ca": d["ca"],
                      "cot": d["cot"]})
            elif tid == 101:
                emit({"event": "counter_interrogation", "ca": d["ca"]})
            elif tid == 103:
                emit({"event": "clock_sync", "ca": d["ca"]})
            elif command_select_bit(data):
                # c104 handles SELECT internally; on_receive only sees EXECUTE
                emit({"event": "command", "type": _type_name(tid),
                      "ioa": d.get("ioa"), "value": decode_command_value(data),
                      "select": True, "cot": COT_NAMES.get(d["cot"], d["cot"]),
                      "raw": data[12:].hex()})

    def _on_send_raw(self, server: c104.Server, data: bytes) -> None:
        # count spontaneous objects that really left (c104's transmit() also
        # returns True for messages its full queue later drops)
        if len(data) > 8 and not data[2] & 0x01 and (data[8] & 0x3F) == 3:
            self.wire_spont_objects += data[7] & 0x7F
        elif len(data) >= 15 and not data[2] & 0x01 and 45 <= data[6] <= 64:
            # what c104 answered to a command (including refusals it makes
            # on its own, e.g. EXECUTE without SELECT, which never reach
            # on_receive)
            d = parse_apdu(data)
            emit({"event": "command_response", "type": _type_name(d["type_id"]),
                  "ioa": d.get("ioa"), "cot": COT_NAMES.get(d["cot"], d["cot"]),
                  "negative": d["negative"], "select": command_select_bit(data)})
        if self.args.raw_log:
            emit({"event": "raw", "dir": "tx", "hex": data.hex(),
                  "explain": c104.explain_bytes(apdu=data)})

    def _on_command(self, point: c104.Point, previous_info: c104.Information,
                    message: c104.IncomingMessage) -> c104.ResponseState:
        ioa = point.io_address
        ctyp, ftyp, sbo, refuse = COMMANDS.get(ioa, (None, None, False, True))
        self.commands_received += 1
        info = point.info
        ev = {"event": "command", "type": point.type.name, "ioa": ioa,
              "value": value_to_json(point.value),
              "select": bool(message.is_select_command),
              "cot": message.cot.name, "time": time_to_json(info.recorded_at),
              "accepted": not refuse}
        ev.update(info_extra(info))
        emit(ev)
        if refuse:
            return c104.ResponseState.FAILURE
        fb = self.feedback.get(ioa)
        if fb is not None:
            self._update_feedback(point, fb)
            if self.args.feedback_cot == "spont":
                t = threading.Timer(self.args.feedback_delay_ms / 1000.0,
                                    self._send_feedback, args=(fb,))
                t.daemon = True
                t.start()
        return c104.ResponseState.SUCCESS

    def _update_feedback(self, cmd_point, fb):
        v = cmd_point.value
        if fb.type == T.M_ST_NA_1:
            pos = int(fb.value)
            if v == c104.Step.HIGHER:
                pos = min(63, pos + 1)
            elif v == c104.Step.LOWER:
                pos = max(-64, pos - 1)
            fb.value = c104.Int7(pos)
        else:
            fb.value = v

    def _send_feedback(self, fb):
        ok = fb.transmit(cause=c104.Cot.SPONTANEOUS)
        emit({"event": "feedback", "type": fb.type.name, "ioa": fb.io_address,
              "value": value_to_json(fb.value), "cot": "SPONTANEOUS", "sent": bool(ok)})

    # ------------------------------------------------------------ spontaneous
    def _spontaneous(self):
        a = self.args
        rate = a.spontaneous_rate
        # wait (bounded by the server lifetime) for a client to send STARTDT
        while not self.stop_event.is_set():
            if self.startdt_event.wait(0.1):
                break
        if self.stop_event.wait(a.spontaneous_delay):
            return
        emit({"event": "spontaneous_started", "rate": rate,
              "count": a.spontaneous_count, "ioas": SPONT_FLOAT_IOAS})
        t0 = time.monotonic()
        k = 0
        n_pts = len(self.spont_points)
        while not self.stop_event.is_set():
            if a.spontaneous_count and k >= a.spontaneous_count:
                break
            due = int((time.monotonic() - t0) * rate)
            if a.spontaneous_count:
                due = min(due, a.spontaneous_count)
            while k < due:
                if a.spontaneous_window and \
                        self.spont_sent - self.wire_spont_objects >= a.spontaneous_window:
                    break  # c104's queue is full enough: wait for the wire
                k += 1
                p = self.spont_points[(k - 1) % n_pts]
                p.value = float(k)
                if p.transmit(cause=c104.Cot.SPONTANEOUS):
                    self.spont_sent += 1
                else:
                    self.spont_failed += 1
            # next event time, sleeping at least 1 ms and at most 50 ms
            nxt = t0 + (k + 1) / rate
            self.stop_event.wait(min(0.05, max(0.001, nxt - time.monotonic())))
        gen_seconds = time.monotonic() - t0
        # let the send queue drain (bounded): wait until the wire count rests
        last, rest_since = -1, time.monotonic()
        dl = Deadline(3.0)
        while not dl.expired() and not self.stop_event.is_set():
            cur = self.wire_spont_objects
            if cur != last:
                last, rest_since = cur, time.monotonic()
            elif time.monotonic() - rest_since > 0.3:
                break
            time.sleep(0.05)
        ev = {"event": "spontaneous_done", "sent": self.spont_sent,
              "failed": self.spont_failed, "on_wire": self.wire_spont_objects,
              "seconds": round(gen_seconds, 3)}
        if gen_seconds > 0:
            ev["per_second"] = round(self.spont_sent / gen_seconds, 1)
        emit(ev)

    # ------------------------------------------------------------ run
    def request_stop(self, reason):
        if self.stop_reason is None:
            self.stop_reason = reason
        self.stop_event.set()

    def _watch_stdin(self):
        try:
            fd = sys.stdin.fileno()
            while os.read(fd, 4096):
                pass
        except Exception:
            pass
        self.request_stop("stdin closed")

    def run(self):
        a = self.args
        deadline = Deadline(a.max_seconds)
        try:
            self.server.start()
        except Exception as e:
            emit({"event": "error", "message": "server start failed: %s" % e})
            return 2
        emit({"event": "ready", "host": a.host, "port": a.port, "ca": a.ca,
              "gi_points": self.gi_points, "pid": os.getpid(),
              "c104_version": c104_version()})
        watch = a.stdin == "watch"
        if a.stdin == "auto":
            try:
                watch = stat.S_ISFIFO(os.fstat(sys.stdin.fileno()).st_mode)
            except Exception:
                watch = False
        if watch:
            threading.Thread(target=self._watch_stdin, daemon=True).start()
        spont = None
        if a.spontaneous_rate > 0:
            spont = threading.Thread(target=self._spontaneous, daemon=True)
            spont.start()
        last_open = 0
        while not self.stop_event.wait(0.1):
            if deadline.expired():
                self.request_stop("max-seconds")
                break
            n = self.server.open_connection_count
            if n < last_open:
                emit({"event": "disconnected", "open_connections": n})
            last_open = n
        if spont is not None:
            spont.join(timeout=2)
        self.server.stop()
        emit({"event": "stopped", "reason": self.stop_reason,
              "commands": self.commands_received,
              "spontaneous_sent": self.spont_sent})
        return 0


def _type_name(tid):
    for name, t in T.__members__.items():
        if int(t.value) == tid:
            return name
    return str(tid)


def main(argv=None):
    args = parse_args(argv)
    if args.spontaneous_rate < 0 or args.points < 0:
        raise SystemExit("negative --spontaneous-rate/--points")
    out = Outstation(args)
    signal.signal(signal.SIGTERM, lambda s, f: out.request_stop("SIGTERM"))
    signal.signal(signal.SIGINT, lambda s, f: out.request_stop("SIGINT"))
    return out.run()


if __name__ == "__main__":
    sys.exit(main())
