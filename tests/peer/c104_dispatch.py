#!/usr/bin/env python3
"""c104 (lib60870-C) as a dispatch system: runs a scenario against an outstation.

Connects to --host:--port (STARTDT as c104_client.py does), then runs the
steps given with --steps in order and stops at the first one that fails:

  {"step": "gi"}                       station interrogation (QOI 20) on --ca,
                                       up to its ACT_TERM
  {"step": "gi", "until_valid": 5}     ... repeated (0.5 s apart) until one
                                       returns no object with IV set, for at
                                       most that many seconds
  {"step": "quiet", "seconds": 1, "timeout": 10}
                                       wait until no object came for that
                                       long, at most timeout s (never fails)
  {"step": "command", "command": "C_SC_NA_1:2021:1"}
                                       a command in c104_client.py's
                                       TYPE:IOA:VALUE[:select][:expect-fail]
  {"step": "expect", "ioa": 291, "value": false, "timeout": 5}
                                       wait for an object with that IOA (and
                                       "value", "type", "cot" when given; cot
                                       defaults to SPONTANEOUS, null = any)
                                       among those received since the last
                                       gi or command step began
  {"step": "sleep", "seconds": 0.5}

One JSON line per received information object (c104_client.py's format),
one result line per step, a final summary (formats in README.md).
Exit 0 = every step passed, 1 = a step failed, 2 = no connection / bad usage.

c104 keeps one point per IOA with one type and drops objects of another
type for an existing point (M_SP_TB_1 events after a GI that taught it
M_SP_NA_1; a monitor point at the IOA of a command point). So this script
creates no monitor points at all: every monitor object reaches
on_unexpected_message as an IncomingMessage that c104 has decoded, and is
read from there. Command points are created for the commands only. What
else c104 finds unexpected (a cause of transmission the type does not
allow, ...) is reported as an unexpected_message line and counted in the
summary's c104_complaints.
"""

import argparse
import json
import math
import sys
import threading
import time

import c104

from c104_client import CommandSpec, Station
from peer_common import (Deadline, c104_version, emit, info_extra, parse_apdu,
                         quality_to_json, time_to_json, value_to_json)

QUALITY_IV = 0x80
# c104 causes for "no point takes this message": its objects are read
DELIVERY_CAUSES = ("UNKNOWN_IOA", "MISMATCHED_TYPE_ID", "UNKNOWN_CA")
STEP_KINDS = ("gi", "quiet", "command", "expect", "sleep")


def load_steps(text):
    """--steps: a JSON list, or @FILE holding one."""
    if text.startswith("@"):
        with open(text[1:], encoding="utf-8") as f:
            text = f.read()
    try:
        steps = json.loads(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError("--steps is not JSON: %s" % e)
    if not isinstance(steps, list):
        raise argparse.ArgumentTypeError("--steps wants a JSON list of steps")
    for step in steps:
        kind = step.get("step") if isinstance(step, dict) else None
        if kind not in STEP_KINDS:
            raise argparse.ArgumentTypeError("unknown step %r" % (step,))
        if kind == "command":
            step["spec"] = CommandSpec(str(step.get("command", "")))
        if kind == "expect" and not isinstance(step.get("ioa"), int):
            raise argparse.ArgumentTypeError("expect step without an integer ioa: %r" % (step,))
    return steps


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=2404)
    p.add_argument("--ca", type=int, default=1, help="common address (1..65534)")
    p.add_argument("--oa", type=int, default=0, help="originator address (0..255)")
    p.add_argument("--steps", required=True, type=load_steps, metavar="JSON|@FILE",
                   help="the scenario: a JSON list of steps, or @FILE")
    p.add_argument("--connect-timeout", type=float, default=10.0)
    p.add_argument("--gi-timeout", type=float, default=10.0,
                   help="seconds to wait for ACT_TERM of a GI")
    p.add_argument("--command-timeout", type=float, default=10.0,
                   help="seconds to wait for ACT_CON / ACT_TERM of a command")
    p.add_argument("--settle", type=float, default=2.0,
                   help="max seconds for c104 to deliver a GI's objects after its ACT_TERM")
    p.add_argument("--raw-log", action="store_true",
                   help="emit a 'raw' line per frame sent and received")
    p.add_argument("--k", type=int, default=None, help="APCI k (c104 default 12)")
    p.add_argument("--w", type=int, default=None, help="APCI w (c104 default 8)")
    p.add_argument("--t1", type=int, default=None, help="APCI t1 seconds (default 15)")
    p.add_argument("--t2", type=int, default=None, help="APCI t2 seconds (default 10)")
    p.add_argument("--t3", type=int, default=None, help="APCI t3 seconds (default 20)")
    a = p.parse_args(argv)
    # what c104_client.Station reads
    a.gi = True
    a.measure_gi = False
    a.quiet_points = False
    return a


def same_value(got, want):
    if isinstance(want, bool) or isinstance(got, bool):
        return got is want
    if isinstance(want, (int, float)) and isinstance(got, (int, float)):
        return math.isclose(got, want, rel_tol=1e-6, abs_tol=1e-9)
    return got == want


class Dispatch(Station):
    def __init__(self, args):
        # received monitor objects, in callback order: (monotonic time, line)
        self.received = []
        self.received_cond = threading.Condition()
        # (cot, negative) of the C_IC_NA_1 responses seen on the wire
        self.gi_wire = []
        self.gi_wire_event = threading.Event()
        # c104's other unexpected-message causes: name -> count
        self.complaints = {}
        super().__init__(args)
        # the one timeout c104 applies to every blocking call (see Station)
        self.c104_timeout = max(args.gi_timeout, args.command_timeout)
        self.con.on_unexpected_message(callable=self._on_message)

    # ------------------------------------------------------------ callbacks
    def _on_rx(self, connection: c104.Connection, data: bytes) -> None:
        super()._on_rx(connection, data)
        d = parse_apdu(data)
        if d is not None and d.get("type_id") == 100:
            with self.lock:
                self.gi_wire.append((d["cot"], d["negative"]))
            self.gi_wire_event.set()

    def _on_new_point(self, client: c104.Client, station: c104.Station,
                      io_address: int, point_type: c104.Type) -> None:
        return None   # no monitor points: see the module docstring

    def _on_message(self, connection: c104.Connection, message: c104.IncomingMessage,
                    cause: c104.Umc) -> None:
        """c104 calls this once per message it cannot deliver to a point
        (DELIVERY_CAUSES), and before that once per irregularity it finds in
        a message (INVALID_COT: e.g. a time-tagged type in a GI answer,
        UNKNOWN_COT, ...): those are complaints, reported, not read."""
        if cause.name not in DELIVERY_CAUSES or int(message.type.value) >= 45:
            # command responses go to the command points and c104 swallows
            # M_EI_NA_1 itself: whatever comes here is worth a line
            with self.lock:
                self.complaints[cause.name] = self.complaints.get(cause.name, 0) + 1
            emit({"event": "unexpected_message", "cause": cause.name,
                  "type": message.type.name, "ioa": message.io_address,
                  "ca": message.common_address, "cot": message.cot.name,
                  "negative": bool(message.is_negative),
                  "objects": message.number_of_objects})
            return
        message.first()
        while message.next():
            info = message.info
            line = {"type": message.type.name, "ioa": message.io_address,
                    "ca": message.common_address,
                    "value": value_to_json(info.value),
                    "quality": quality_to_json(info.quality),
                    "cot": message.cot.name, "time": time_to_json(info.recorded_at),
                    "negative": bool(message.is_negative),
                    "test": bool(message.is_test)}
            line.update(info_extra(info))
            emit(line)
            with self.lock:
                self.objects += 1
                if message.cot == c104.Cot.INTERROGATED_BY_STATION:
                    self.gi_objects += 1
            with self.received_cond:
                self.received.append((time.monotonic(), line))
                self.received_cond.notify_all()

    def mark(self):
        with self.received_cond:
            return len(self.received), time.monotonic()

    def missed_response(self, c104_ok, seconds, complete):
        """c104 2.2.1 loses the wake-up of a blocking call when the whole
        response (ACT_CON, and ACT_TERM where awaited) is processed before
        the calling thread starts waiting for it: the call then returns False
        after the full timeout. Its debug trace shows it (set_command_success
        ... found: 1 before await_command_success] Await, then Timeout).
        True when that is what happened: the response is complete and
        positive on the wire and c104 gave up after its timeout."""
        return not c104_ok and complete and seconds >= 0.9 * self.c104_timeout

    # ------------------------------------------------------------ steps
    def gi_round(self, number):
        """One GI: returns (ok, invalid IOAs) once its ACT_TERM came and c104
        delivered all of its objects (callbacks run from a queue: as many as
        the raw frames counted, bounded by --settle). ok = positive ACT_CON
        and ACT_TERM on the wire, and c104 reported success."""
        with self.lock:
            raw_before = self.gi_raw_objects
            decoded_before = self.gi_objects
            wire_before = len(self.gi_wire)
        start, _ = self.mark()
        t0 = time.perf_counter()
        c104_ok = bool(self.con.interrogation(common_address=self.args.ca,
                                              cause=c104.Cot.ACTIVATION,
                                              qualifier=c104.Qoi.STATION,
                                              wait_for_response=True))
        c104_seconds = time.perf_counter() - t0
        dl = Deadline(self.args.gi_timeout)
        while True:
            with self.lock:
                wire = self.gi_wire[wire_before:]
            confirmed = (7, False) in wire
            refused = any(negative for _, negative in wire)
            terminated = any(cot == 10 for cot, _ in wire)
            if refused or terminated or dl.expired():
                break
            self.gi_wire_event.wait(0.05)
            self.gi_wire_event.clear()
        seconds = time.perf_counter() - t0
        complete = confirmed and terminated and not refused
        missed = self.missed_response(c104_ok, c104_seconds, complete)
        ok = complete and (c104_ok or missed)
        dl = Deadline(self.args.settle)
        while True:
            with self.lock:
                raw = self.gi_raw_objects - raw_before
                decoded = self.gi_objects - decoded_before
            if decoded >= raw or dl.expired():
                break
            time.sleep(0.02)
        with self.received_cond:
            answer = [line for _, line in self.received[start:]
                      if line["cot"] == "INTERROGATED_BY_STATION"]
        invalid = sorted({line["ioa"] for line in answer
                          if isinstance(line["quality"], int) and line["quality"] & QUALITY_IV})
        result = {"event": "gi_done", "round": number, "ok": ok, "c104_ok": c104_ok,
                  "confirmed": confirmed, "terminated": terminated,
                  "seconds": round(seconds, 6), "objects": raw, "decoded_objects": decoded,
                  "invalid": len(invalid), "invalid_ioas": invalid[:20]}
        if missed:
            result["c104_missed_response"] = True
        emit(result)
        return ok, invalid

    def step_gi(self, step):
        until_valid = step.get("until_valid")
        dl = Deadline(until_valid or 0)
        number = 0
        while True:
            number += 1
            ok, invalid = self.gi_round(number)
            if not ok:
                return "gi %d not confirmed/terminated" % number
            if until_valid is None or not invalid:
                return None
            if dl.expired():
                return "gi: %d object(s) still invalid after %.1f s, e.g. %s" % (
                    len(invalid), until_valid, invalid[:10])
            time.sleep(min(0.5, dl.remaining()))

    def step_quiet(self, step):
        quiet_for = float(step.get("seconds", 1.0))
        dl = Deadline(float(step.get("timeout", 10.0)))
        t0 = time.monotonic()
        while True:
            with self.received_cond:
                last = self.received[-1][0] if self.received else t0
            idle = time.monotonic() - max(last, t0)
            if idle >= quiet_for or dl.expired():
                break
            time.sleep(min(0.05, dl.remaining()) or 0.01)
        emit({"event": "quiet_done", "quiet": idle >= quiet_for,
              "seconds": round(time.monotonic() - t0, 3)})
        return None

    def command(self, spec):
        """c104_client.Station.command, plus the lost wake-up above: the
        result line says c104_missed_response when the command counts as
        confirmed from the wire although c104 returned False."""
        station = self.con.get_station(self.args.ca) or self.con.add_station(self.args.ca)
        typ = getattr(c104.Type, spec.type_name)
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
        complete = confirm == "positive" and (terminated or not spec.select)
        missed = self.missed_response(c104_ok, dt, complete)
        ok = complete and (c104_ok or missed)
        result = {"event": "command_result", "type": spec.type_name, "ioa": spec.ioa,
                  "value": value_to_json(p.value), "select": spec.select, "ok": ok,
                  "expected_ok": not spec.expect_fail, "c104_ok": c104_ok,
                  "confirm": confirm, "terminated": terminated, "cots": cots,
                  "sequence": sequence, "seconds": round(dt, 6)}
        if missed:
            result["c104_missed_response"] = True
        emit(result)
        return ok == (not spec.expect_fail), ok

    def step_command(self, step):
        as_expected, ok = self.command(step["spec"])
        if as_expected:
            return None
        return "command %s: ok=%s" % (step["spec"].text, ok)

    def step_expect(self, step, since, since_time):
        want_cot = step.get("cot", "SPONTANEOUS")
        timeout = float(step.get("timeout", 5.0))

        def matches(line):
            return (line["ioa"] == step["ioa"]
                    and ("value" not in step or same_value(line["value"], step["value"]))
                    and ("type" not in step or line["type"] == step["type"])
                    and (want_cot is None or line["cot"] == want_cot))

        dl = Deadline(timeout)
        with self.received_cond:
            while True:
                found = next(((t, line) for t, line in self.received[since:] if matches(line)),
                             None)
                if found is not None or dl.expired():
                    break
                self.received_cond.wait(min(0.1, dl.remaining()))
            seen = [line for _, line in self.received[since:] if line["ioa"] == step["ioa"]]
        result = {"event": "expect_done", "ioa": step["ioa"], "ok": found is not None}
        for key in ("value", "type"):
            if key in step:
                result[key] = step[key]
        result["cot"] = want_cot
        if found is not None:
            t, line = found
            result.update({"seconds": round(t - since_time, 6), "object": line})
        else:
            result.update({"timeout": timeout, "seen": seen[-5:]})
        emit(result)
        if found is not None:
            return None
        wanted = {k: step[k] for k in ("value", "type") if k in step}
        return "expect ioa %d %s cot %s: not within %.1f s (seen %s)" % (
            step["ioa"], wanted, want_cot, timeout, seen[-5:])


def main(argv=None):
    args = parse_args(argv)
    st = Dispatch(args)
    summary = {"event": "summary", "ok": False, "c104_version": c104_version(),
               "steps": len(args.steps), "steps_done": 0}
    failures = []
    try:
        if not st.connect():
            summary["failures"] = ["connect"]
            emit(summary)
            return 2
        since, since_time = st.mark()
        for index, step in enumerate(args.steps):
            kind = step["step"]
            if kind in ("gi", "command"):
                since, since_time = st.mark()
            if kind == "gi":
                failure = st.step_gi(step)
            elif kind == "quiet":
                failure = st.step_quiet(step)
            elif kind == "command":
                failure = st.step_command(step)
            elif kind == "expect":
                failure = st.step_expect(step, since, since_time)
            else:
                time.sleep(float(step.get("seconds", 0)))
                failure = None
            if failure is not None:
                failures.append("step %d: %s" % (index, failure))
                break
            summary["steps_done"] = index + 1
        with st.lock:
            summary.update({
                "objects": st.objects,
                "raw_rx_frames": dict(st.raw_rx),
                "raw_objects_by_cot": dict(sorted(st.raw_objects_by_cot.items())),
                "raw_asdus_by_type": dict(sorted(st.raw_asdus_by_type.items())),
                "spontaneous": st.spont_raw_objects,
                "c104_complaints": dict(sorted(st.complaints.items())),
            })
        summary["ok"] = not failures
        summary["failures"] = failures
        emit(summary)
        return 1 if failures else 0
    finally:
        st.stop()


if __name__ == "__main__":
    sys.exit(main())
