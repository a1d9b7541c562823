#!/usr/bin/env python3
"""c104 (lib60870-C) IEC 60870-5-104 controlling station for interop tests.

Connects to --host:--port, sends STARTDT, then in this order:
  1. --gi / --measure-gi: station interrogation (QOI 20) on --ca, waits for
     ACT_TERM (timed: the call blocks in c104 from sending ACT to receiving
     ACT_TERM),
  2. each --command in the order given (waits for ACT_CON, and for ACT_TERM
     when select-before-operate is used),
  3. listens for --duration seconds (or until --expect-spontaneous objects
     came),
then prints a summary line and exits: 0 = all expectations met, 1 = an
expectation failed, 2 = could not connect / bad usage.

One JSON line per received information object, per command result, and a
final summary (formats in README.md).

--command TYPE:IOA:VALUE[:select][:expect-fail]
  TYPE   C_SC_NA_1 C_SC_TA_1 (VALUE 0/1/true/false/on/off)
         C_DC_NA_1 C_DC_TA_1 (VALUE 1/2 or OFF/ON; 0/3 are sent as given)
         C_RC_NA_1 C_RC_TA_1 (VALUE 1/2 or LOWER/HIGHER)
         C_SE_NA_1 C_SE_TA_1 (VALUE -1.0..1.0)
         C_SE_NB_1 C_SE_TB_1 (VALUE -32768..32767)
         C_SE_NC_1 C_SE_TC_1 (VALUE float)
         C_BO_NA_1 C_BO_TA_1 (VALUE unsigned 32-bit int, 0x.. allowed)
  select       select-before-operate (SELECT, ACT_CON, EXECUTE, ACT_CON, ACT_TERM)
  expect-fail  the command is expected to be refused (negative ACT_CON or timeout)
"""

import argparse
import sys
import threading
import time

import c104

from peer_common import (Deadline, apply_apci, c104_version, command_select_bit, emit,
                         info_extra, parse_apdu, quality_to_json, time_to_json,
                         value_to_json)

T = c104.Type

COMMAND_TYPES = {
    "C_SC_NA_1", "C_SC_TA_1", "C_DC_NA_1", "C_DC_TA_1", "C_RC_NA_1", "C_RC_TA_1",
    "C_SE_NA_1", "C_SE_TA_1", "C_SE_NB_1", "C_SE_TB_1", "C_SE_NC_1", "C_SE_TC_1",
    "C_BO_NA_1", "C_BO_TA_1",
}

# COT value -> c104 name, for the raw counters
COT_NAMES = {int(v.value): n for n, v in c104.Cot.__members__.items()}
TYPE_NAMES = {int(v.value): n for n, v in T.__members__.items()}


class CommandSpec:
    def __init__(self, text):
        parts = text.split(":")
        if len(parts) < 3:
            raise argparse.ArgumentTypeError(
                "--command wants TYPE:IOA:VALUE[:select][:expect-fail], got %r" % text)
        self.text = text
        self.type_name = parts[0].upper()
        if self.type_name not in COMMAND_TYPES:
            raise argparse.ArgumentTypeError("unsupported command type %r" % parts[0])
        try:
            self.ioa = int(parts[1], 0)
        except ValueError:
            raise argparse.ArgumentTypeError("bad IOA in %r" % text)
        self.raw_value = parts[2]
        flags = {f.lower() for f in parts[3:] if f}
        unknown = flags - {"select", "sbo", "expect-fail"}
        if unknown:
            raise argparse.ArgumentTypeError("unknown flag(s) %s in %r" % (sorted(unknown), text))
        self.select = bool(flags & {"select", "sbo"})
        self.expect_fail = "expect-fail" in flags
        self.value = self._convert(self.type_name, self.raw_value)

    @staticmethod
    def _convert(tn, s):
        ls = s.strip().lower()
        try:
            if tn.startswith("C_SC"):
                if ls in ("1", "true", "on"):
                    return True
                if ls in ("0", "false", "off"):
                    return False
                raise ValueError
            if tn.startswith("C_DC"):
                names = {"intermediate": 0, "off": 1, "on": 2, "indeterminate": 3}
                n = names[ls] if ls in names else int(ls, 0)
                return {0: c104.Double.INTERMEDIATE, 1: c104.Double.OFF,
                        2: c104.Double.ON, 3: c104.Double.INDETERMINATE}[n]
            if tn.startswith("C_RC"):
                names = {"invalid_0": 0, "lower": 1, "higher": 2, "invalid_3": 3}
                n = names[ls] if ls in names else int(ls, 0)
                return {0: c104.Step.INVALID_0, 1: c104.Step.LOWER,
                        2: c104.Step.HIGHER, 3: c104.Step.INVALID_3}[n]
            if tn in ("C_SE_NA_1", "C_SE_TA_1"):
                return c104.NormalizedFloat(float(s))
            if tn in ("C_SE_NB_1", "C_SE_TB_1"):
                return c104.Int16(int(s, 0))
            if tn in ("C_SE_NC_1", "C_SE_TC_1"):
                return float(s)
            if tn.startswith("C_BO"):
                n = int(s, 0)
                return c104.Byte32((n & 0xFFFFFFFF).to_bytes(4, "little"))
        except (ValueError, KeyError):
            pass
        raise argparse.ArgumentTypeError("bad value %r for %s" % (s, tn))


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=2404)
    p.add_argument("--ca", type=int, default=1, help="common address (1..65534)")
    p.add_argument("--oa", type=int, default=0, help="originator address (0..255)")
    p.add_argument("--gi", action="store_true", help="send a station interrogation")
    p.add_argument("--measure-gi", action="store_true",
                   help="benchmark mode: GI only timed; objects counted from raw "
                        "frames, no per-object lines, no c104 point objects")
    p.add_argument("--command", action="append", default=[], type=CommandSpec,
                   metavar="TYPE:IOA:VALUE[:select][:expect-fail]")
    p.add_argument("--duration", type=float, default=0.0,
                   help="seconds to keep listening after GI/commands")
    p.add_argument("--expect-points", type=int, default=None,
                   help="fail unless the GI returned at least N objects")
    p.add_argument("--expect-spontaneous", type=int, default=None,
                   help="fail unless N objects with COT spontaneous came; listening "
                        "ends as soon as they did (bounded by --duration)")
    p.add_argument("--quiet-points", action="store_true",
                   help="no decoding: no line per received object, objects are "
                        "only counted from raw frames (fast)")
    p.add_argument("--connect-timeout", type=float, default=10.0)
    p.add_argument("--gi-timeout", type=float, default=120.0,
                   help="seconds to wait for ACT_TERM of the GI")
    p.add_argument("--command-timeout", type=float, default=10.0,
                   help="seconds to wait for ACT_CON / ACT_TERM of a command")
    p.add_argument("--settle", type=float, default=2.0,
                   help="max seconds to let c104 deliver queued callbacks after the GI")
    p.add_argument("--raw-log", action="store_true",
                   help="emit a 'raw' line per frame sent and received")
    p.add_argument("--k", type=int, default=None, help="APCI k (c104 default 12)")
    p.add_argument("--w", type=int, default=None, help="APCI w (c104 default 8)")
    p.add_argument("--t1", type=int, default=None, help="APCI t1 seconds (default 15)")
    p.add_argument("--t2", type=int, default=None, help="APCI t2 seconds (default 10)")
    p.add_argument("--t3", type=int, default=None, help="APCI t3 seconds (default 20)")
    a = p.parse_args(argv)
    if a.measure_gi:
        a.gi = True
        a.quiet_points = True
    return a


class Station:
    def __init__(self, args):
        self.args = args
        self.lock = threading.Lock()
        # counters from raw frames (exact, one callback per APDU)
        self.raw_rx = {"I": 0, "S": 0, "U": 0}
        self.raw_tx = {"I": 0, "S": 0, "U": 0}
        self.raw_objects_by_cot = {}
        self.raw_asdus_by_type = {}
        self.gi_raw_objects = 0
        self.gi_raw_asdus = 0
        self.spont_raw_objects = 0
        # counters from decoded objects (point callbacks)
        self.objects = 0
        self.objects_by_type = {}
        self.objects_by_cot = {}
        self.gi_objects = 0
        self.spont_objects = 0
        self.spont_first_raw = None
        self.spont_last_raw = None
        # (type id, ioa) -> [(cot, negative, select bit)] of command
        # responses seen on the wire, for the command being sent
        self.cmd_wire = {}
        self.cmd_wire_event = threading.Event()
        # every I frame's (type, cause) in wire order while a command is open: the order
        # of its confirmation, return information and termination
        self.cmd_sequence = []

        timeout_s = max(args.gi_timeout if args.gi else 0, args.command_timeout)
        self.client = c104.Client(tick_rate_ms=100,
                                  command_timeout_ms=int(timeout_s * 1000))
        if args.oa:
            self.client.originator_address = args.oa
        self.con = self.client.add_connection(ip=args.host, port=args.port,
                                              init=c104.Init.NONE)
        if self.con is None:
            raise SystemExit("cannot add connection")
        apply_apci(self.con.protocol_parameters, args)
        self.con.on_receive_raw(callable=self._on_rx)
        if args.raw_log:
            self.con.on_send_raw(callable=self._on_tx)
        if args.quiet_points:
            # count from raw frames only: no decoding in Python (c104 then
            # runs at lib60870 speed) and no c104 point objects (its point
            # list is linear: adding N points is O(N^2))
            self.client.on_new_point(callable=self._on_new_point_ignore)
        else:
            self.client.on_new_point(callable=self._on_new_point)

    # ------------------------------------------------------------ callbacks
    def _on_tx(self, connection: c104.Connection, data: bytes) -> None:
        emit({"event": "raw", "dir": "tx", "hex": data.hex(),
              "explain": c104.explain_bytes(apdu=data)})

    def _on_rx(self, connection: c104.Connection, data: bytes) -> None:
        if self.args.raw_log:
            emit({"event": "raw", "dir": "rx", "hex": data.hex(),
                  "explain": c104.explain_bytes(apdu=data)})
        d = parse_apdu(data)
        if d is None:
            return
        with self.lock:
            self.raw_rx[d["frame"]] += 1
            if d["frame"] != "I" or "type_id" not in d:
                return
            tid, cot, n = d["type_id"], d["cot"], d["n"]
            tn = TYPE_NAMES.get(tid, str(tid))
            if self.cmd_wire:
                self.cmd_sequence.append([tn, cot])
            if 45 <= tid <= 64 and "ioa" in d:
                key = (tid, d["ioa"])
                if key in self.cmd_wire:
                    self.cmd_wire[key].append((cot, d["negative"],
                                               command_select_bit(data)))
                    self.cmd_wire_event.set()
            self.raw_asdus_by_type[tn] = self.raw_asdus_by_type.get(tn, 0) + 1
            if tid < 45:  # monitor direction information objects
                cn = COT_NAMES.get(cot, str(cot))
                self.raw_objects_by_cot[cn] = self.raw_objects_by_cot.get(cn, 0) + n
                if cot == 20:
                    self.gi_raw_objects += n
                    self.gi_raw_asdus += 1
                elif cot == 3:
                    self.spont_raw_objects += n
                    now = time.monotonic()
                    if self.spont_first_raw is None:
                        self.spont_first_raw = now
                    self.spont_last_raw = now

    def _on_new_point_ignore(self, client: c104.Client, station: c104.Station,
                             io_address: int, point_type: c104.Type) -> None:
        return None

    def _on_new_point(self, client: c104.Client, station: c104.Station,
                      io_address: int, point_type: c104.Type) -> None:
        p = station.add_point(io_address=io_address, type=point_type)
        if p is not None:
            p.on_receive(callable=self._on_point)

    def _on_point(self, point: c104.Point, previous_info: c104.Information,
                  message: c104.IncomingMessage) -> c104.ResponseState:
        tn = point.type.name
        cot = message.cot
        with self.lock:
            self.objects += 1
            self.objects_by_type[tn] = self.objects_by_type.get(tn, 0) + 1
            self.objects_by_cot[cot.name] = self.objects_by_cot.get(cot.name, 0) + 1
            if cot == c104.Cot.INTERROGATED_BY_STATION:
                self.gi_objects += 1
            elif cot == c104.Cot.SPONTANEOUS:
                self.spont_objects += 1
        if not self.args.quiet_points:
            info = point.info
            ev = {"type": tn, "ioa": point.io_address,
                  "ca": message.common_address,
                  "value": value_to_json(point.value),
                  "quality": quality_to_json(info.quality),
                  "cot": cot.name, "time": time_to_json(info.recorded_at),
                  "negative": bool(message.is_negative),
                  "test": bool(message.is_test)}
            ev.update(info_extra(info))
            emit(ev)
        return c104.ResponseState.NONE

    # ------------------------------------------------------------ steps
    def connect(self):
        """Start the client and wait until STARTDT is confirmed.

        c104 2.2.1 sometimes never sends STARTDT act after the TCP connect
        (its task loop misses the wake-up); if the connection sits in
        OPEN_MUTED for 0.3 s we send STARTDT ourselves (con.unmute()),
        at most 5 times."""
        self.client.start()
        dl = Deadline(self.args.connect_timeout)
        kicks = 0
        muted_since = None
        while not dl.expired():
            s = self.con.state
            if s == c104.ConnectionState.OPEN:
                emit({"event": "connected", "host": self.args.host,
                      "port": self.args.port, "startdt_kicks": kicks})
                return True
            if s == c104.ConnectionState.OPEN_MUTED:
                if muted_since is None:
                    muted_since = time.monotonic()
                elif time.monotonic() - muted_since > 0.3 and kicks < 5:
                    self.con.unmute()
                    kicks += 1
                    muted_since = time.monotonic()
            else:
                muted_since = None
            time.sleep(0.02)
        emit({"event": "error", "message": "no active connection to %s:%d within %.1fs (state %s)"
              % (self.args.host, self.args.port, self.args.connect_timeout, self.con.state.name)})
        return False

    def _counts(self):
        with self.lock:
            return (self.objects, self.gi_raw_objects)

    def settle(self, want=None):
        """c104 delivers point callbacks from a task queue: wait until the
        counters stop moving (bounded by --settle)."""
        dl = Deadline(self.args.settle)
        last = self._counts()
        stable_since = time.monotonic()
        while not dl.expired():
            time.sleep(0.05)
            cur = self._counts()
            if cur != last:
                last = cur
                stable_since = time.monotonic()
                continue
            if want is not None and not self.args.measure_gi and cur[0] < want:
                # point callbacks still behind the raw frames
                continue
            if time.monotonic() - stable_since >= 0.2:
                return

    def gi(self):
        t0 = time.perf_counter()
        ok = self.con.interrogation(common_address=self.args.ca,
                                    cause=c104.Cot.ACTIVATION,
                                    qualifier=c104.Qoi.STATION,
                                    wait_for_response=True)
        dt = time.perf_counter() - t0
        self.settle()
        with self.lock:
            raw_n, raw_asdus, dec_n = self.gi_raw_objects, self.gi_raw_asdus, self.gi_objects
        ev = {"event": "gi_done", "ok": bool(ok), "seconds": round(dt, 6),
              "objects": raw_n, "asdus": raw_asdus}
        if not self.args.measure_gi:
            ev["decoded_objects"] = dec_n
        if ok and dt > 0:
            ev["objects_per_second"] = round(raw_n / dt, 1)
        emit(ev)
        return bool(ok), dt, raw_n

    def command(self, spec):
        station = self.con.get_station(self.args.ca) or self.con.add_station(self.args.ca)
        typ = getattr(T, spec.type_name)
        p = station.get_point(spec.ioa)
        if p is not None and p.type != typ:
            station.remove_point(spec.ioa)
            p = None
        if p is None:
            p = station.add_point(io_address=spec.ioa, type=typ)
        p.command_mode = (c104.CommandMode.SELECT_AND_EXECUTE if spec.select
                          else c104.CommandMode.DIRECT)
        p.value = spec.value
        key = (int(typ.value), spec.ioa)
        with self.lock:
            self.cmd_wire[key] = []
            self.cmd_sequence = []
        self.cmd_wire_event.clear()
        t0 = time.perf_counter()
        c104_ok = bool(p.transmit(cause=c104.Cot.ACTIVATION))
        dt = time.perf_counter() - t0
        confirm, terminated, cots = self._wire_result(key, spec.select)
        if confirm == "positive" and not terminated:
            terminated = self._await_termination(key)
        with self.lock:
            self.cmd_wire.pop(key, None)
            sequence = list(self.cmd_sequence)
        # c104 2.2.1 can report success for a refused command: a negative
        # ACT_CON followed at once by e.g. COT 47 (unknown IOA) flips its
        # result back to "success". Trust the frames on the wire as well.
        ok = c104_ok and confirm == "positive" and (terminated or not spec.select)
        emit({"event": "command_result", "type": spec.type_name, "ioa": spec.ioa,
              "value": value_to_json(p.value), "select": spec.select, "ok": ok,
              "expected_ok": not spec.expect_fail, "c104_ok": c104_ok,
              "confirm": confirm, "terminated": terminated, "cots": cots,
              "sequence": sequence, "seconds": round(dt, 6)})
        return ok == (not spec.expect_fail), ok

    def _await_termination(self, key):
        """A direct command returns at its ACT_CON: wait (bounded) for the termination,
        so that the wire order of return information and ACT_TERM is seen whole.
        True when it came."""
        dl = Deadline(8.0)
        while not dl.expired():
            with self.lock:
                if any(cot == 10 for cot, _, _ in self.cmd_wire.get(key, [])):
                    return True
            self.cmd_wire_event.wait(0.05)
            self.cmd_wire_event.clear()
        return False

    def _wire_result(self, key, select):
        """Wait (at most 2 s; c104 runs callbacks from a queue) for the
        confirmation of the EXECUTE on the wire and read it:
        confirm = positive | negative | none, terminated = ACT_TERM seen."""
        dl = Deadline(2.0)
        while True:
            with self.lock:
                seen = list(self.cmd_wire.get(key, []))
            confirm = "none"
            terminated = False
            for cot, neg, sel in seen:
                if cot == 7 and not sel:
                    confirm = "negative" if neg else ("positive" if confirm != "negative" else confirm)
                elif cot == 7 and sel and neg:
                    confirm = "negative"   # select refused
                elif cot in (44, 45, 46, 47):
                    confirm = "negative"
                elif cot == 10:
                    terminated = True
            done = confirm == "negative" or (confirm == "positive" and (terminated or not select))
            if done or dl.expired():
                # a refusal may be followed by a COT 44..47 mirror: give it a moment
                return confirm, terminated, [COT_NAMES.get(c, str(c)) + (":negative" if n else "")
                                             for c, n, _ in seen]
            self.cmd_wire_event.wait(0.05)
            self.cmd_wire_event.clear()

    def listen(self, seconds, expect_spont):
        dl = Deadline(seconds)
        while not dl.expired():
            if expect_spont is not None:
                with self.lock:
                    n = self.spont_raw_objects
                if n >= expect_spont:
                    break
            time.sleep(0.05)

    def stop(self):
        try:
            self.client.stop()
        except Exception:
            pass


def main(argv=None):
    args = parse_args(argv)
    st = Station(args)
    summary = {"event": "summary", "ok": False, "c104_version": c104_version()}
    failures = []
    rc = 2
    try:
        if not st.connect():
            summary["failures"] = ["connect"]
            emit(summary)
            return 2
        rc = 0
        if args.gi:
            ok, dt, n = st.gi()
            summary.update({"gi_ok": ok, "gi_seconds": round(dt, 6), "points": n})
            if not ok:
                failures.append("gi not confirmed/terminated")
            if args.expect_points is not None and n < args.expect_points:
                failures.append("gi returned %d objects, expected >= %d" % (n, args.expect_points))
        cmd_ok = cmd_bad = 0
        for spec in args.command:
            as_expected, ok = st.command(spec)
            if ok:
                cmd_ok += 1
            else:
                cmd_bad += 1
            if not as_expected:
                failures.append("command %s: ok=%s" % (spec.text, ok))
        if args.command:
            summary.update({"commands_ok": cmd_ok, "commands_failed": cmd_bad})
        listen_for = args.duration
        if args.expect_spontaneous is not None and listen_for <= 0:
            listen_for = 30.0
        if listen_for > 0:
            st.listen(listen_for, args.expect_spontaneous)
        st.settle()
        with st.lock:
            summary.update({
                "objects": st.objects,
                "objects_by_type": dict(sorted(st.objects_by_type.items())),
                "objects_by_cot": dict(sorted(st.objects_by_cot.items())),
                "raw_rx_frames": dict(st.raw_rx),
                "raw_objects_by_cot": dict(sorted(st.raw_objects_by_cot.items())),
                "raw_asdus_by_type": dict(sorted(st.raw_asdus_by_type.items())),
                "spontaneous": st.spont_raw_objects,
            })
            if st.spont_first_raw is not None and st.spont_last_raw is not None:
                # callback times (c104 queues callbacks: approximate)
                span = st.spont_last_raw - st.spont_first_raw
                summary["spontaneous_span_seconds"] = round(span, 6)
                if span > 0 and st.spont_raw_objects > 1:
                    summary["spontaneous_per_second"] = round((st.spont_raw_objects - 1) / span, 1)
            if args.expect_spontaneous is not None and st.spont_raw_objects < args.expect_spontaneous:
                failures.append("got %d spontaneous objects, expected >= %d"
                                % (st.spont_raw_objects, args.expect_spontaneous))
        if failures:
            rc = 1
        summary["ok"] = not failures
        summary["failures"] = failures
        emit(summary)
        return rc
    finally:
        st.stop()


if __name__ == "__main__":
    sys.exit(main())
