"""Helpers shared by c104_server.py and c104_client.py.

Only the standard library and c104 are used. Everything printed goes through
emit(): one JSON object per line on stdout, flushed at once, so a test harness
can follow the peer line by line.
"""

import json
import math
import os
import sys
import threading
import time

import c104

_emit_lock = threading.Lock()


def c104_version():
    try:
        import c104._c104 as _m
        return getattr(_m, "__version__", None)
    except Exception:  # pragma: no cover - defensive
        return None


def emit(obj):
    """Print one JSON line and flush (thread-safe)."""
    line = json.dumps(obj, separators=(",", ":"), allow_nan=False,
                      default=str)
    with _emit_lock:
        try:
            sys.stdout.write(line + "\n")
            sys.stdout.flush()
        except BrokenPipeError:
            # the reader went away: keep running, print nowhere
            try:
                devnull = os.open(os.devnull, os.O_WRONLY)
                os.dup2(devnull, sys.stdout.fileno())
            except OSError:
                pass


def _num(x):
    x = float(x)
    if math.isnan(x) or math.isinf(x):
        return str(x)
    return x


def value_to_json(v):
    """Convert a c104 value (point.value) to a plain JSON value.

    bool -> bool; float -> number; int -> int;
    c104.Double / c104.Step / c104.EventState -> their IEC integer (DPI 0..3,
    RCS 0..3, ...); Int7 / Int16 / UInt5 / UInt7 / UInt16 -> int;
    NormalizedFloat -> float; Byte32 -> unsigned int of the 4 wire octets read
    little-endian (as on the wire, first octet = bits 1..8);
    flag sets (PackedSingle, StartEvents, OutputCircuits) -> int bits.
    """
    if v is None or isinstance(v, bool):
        return v
    if isinstance(v, int):
        return v
    if isinstance(v, float):
        return _num(v)
    if isinstance(v, c104.Byte32):
        return int.from_bytes(bytes(v), "little")
    if isinstance(v, (c104.Double, c104.Step, c104.EventState)):
        return int(v.value)
    if isinstance(v, c104.NormalizedFloat):
        return _num(v)
    if isinstance(v, (c104.Int7, c104.Int16, c104.UInt5, c104.UInt7,
                      c104.UInt16)):
        return int(v)
    val = getattr(v, "value", None)
    if isinstance(val, (int, bool)):
        return int(val)
    try:
        return int(v)
    except Exception:
        return str(v)


def quality_to_json(q):
    """Quality bits exactly as on the wire (IV=0x80 NT=0x40 SB=0x20 BL=0x10
    OV=0x01; for counters IV=0x80 CA=0x40 CY=0x20); 0 = good; None when the
    type carries no quality (commands, M_ME_ND_1)."""
    if q is None:
        return None
    try:
        return int(q.value)
    except Exception:
        return str(q)


def time_to_json(dt):
    if dt is None:
        return None
    try:
        return dt.isoformat()
    except Exception:
        return str(dt)


def info_extra(info):
    """Type-specific extra fields of an Information object."""
    extra = {}
    if isinstance(info, c104.StepInfo):
        extra["transient"] = bool(info.transient)
    elif isinstance(info, c104.BinaryCounterInfo):
        extra["sequence"] = int(info.sequence)
    elif isinstance(info, (c104.SingleCmd, c104.DoubleCmd, c104.StepCmd)):
        extra["qualifier"] = int(info.qualifier.value)
    elif isinstance(info, (c104.NormalizedCmd, c104.ScaledCmd,
                           c104.ShortCmd)):
        extra["qualifier"] = int(info.qualifier)
    elif isinstance(info, c104.StatusAndChanged):
        extra["changed"] = value_to_json(info.changed)
    return extra


class Deadline:
    """A monotonic deadline; remaining() never goes below 0."""

    def __init__(self, seconds):
        self.end = time.monotonic() + max(0.0, float(seconds))

    def remaining(self):
        return max(0.0, self.end - time.monotonic())

    def expired(self):
        return time.monotonic() >= self.end


def parse_apdu(data):
    """Minimal decode of one raw APDU (bytes starting with 0x68), for
    counting and for spotting what c104 does not surface (select commands,
    U frames). Assumes the 104 defaults c104 uses: COT 2 octets, CA 2
    octets, IOA 3 octets. Returns a dict or None."""
    if len(data) < 6 or data[0] != 0x68:
        return None
    c1 = data[2]
    if c1 & 0x01 == 0:
        d = {"frame": "I"}
        if len(data) >= 12:
            d["type_id"] = data[6]
            d["sq"] = bool(data[7] & 0x80)
            d["n"] = data[7] & 0x7F
            d["cot"] = data[8] & 0x3F
            d["negative"] = bool(data[8] & 0x40)
            d["test"] = bool(data[8] & 0x80)
            d["oa"] = data[9]
            d["ca"] = data[10] | (data[11] << 8)
            if len(data) >= 15:
                d["ioa"] = data[12] | (data[13] << 8) | (data[14] << 16)
        return d
    if c1 & 0x03 == 0x01:
        return {"frame": "S"}
    u = {0x07: "STARTDT_ACT", 0x0B: "STARTDT_CON", 0x13: "STOPDT_ACT",
         0x23: "STOPDT_CON", 0x43: "TESTFR_ACT", 0x83: "TESTFR_CON"}
    return {"frame": "U", "u": u.get(c1, "0x%02x" % c1)}


# type id -> offset of the octet that holds the S/E bit, counted from the
# first octet after the IOA (single-object command ASDUs)
_SE_OFFSET = {45: 0, 46: 0, 47: 0, 48: 2, 49: 2, 50: 4,
              58: 0, 59: 0, 60: 0, 61: 2, 62: 2, 63: 4}


def command_select_bit(data):
    """For a raw command APDU return True (select), False (execute) or None
    (not a command with an S/E bit)."""
    if len(data) < 16 or data[2] & 0x01:
        return None
    off = _SE_OFFSET.get(data[6])
    if off is None or len(data) <= 15 + off:
        return None
    return bool(data[15 + off] & 0x80)


def decode_command_value(data):
    """Value of a raw single-object command APDU, in the same JSON form as
    value_to_json() (used for SELECT frames, which c104 does not surface)."""
    import struct
    if len(data) < 16:
        return None
    tid = data[6]
    b = data[15:]
    try:
        if tid in (45, 58):
            return bool(b[0] & 0x01)
        if tid in (46, 59, 47, 60):
            return b[0] & 0x03
        if tid in (48, 61):
            return struct.unpack("<h", b[0:2])[0] / 32768.0
        if tid in (49, 62):
            return struct.unpack("<h", b[0:2])[0]
        if tid in (50, 63):
            return _num(struct.unpack("<f", b[0:4])[0])
        if tid in (51, 64):
            return int.from_bytes(b[0:4], "little")
    except (IndexError, struct.error):
        return None
    return None


def apply_apci(params, args):
    """Set k, w, t1, t2, t3 on a c104 ProtocolParameters when given."""
    for attr, name in (("send_window_size", "k"), ("receive_window_size", "w"),
                       ("message_timeout", "t1"), ("confirm_interval", "t2"),
                       ("keep_alive_interval", "t3")):
        v = getattr(args, name, None)
        if v is not None:
            setattr(params, attr, v)
