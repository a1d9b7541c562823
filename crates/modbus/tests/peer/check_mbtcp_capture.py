#!/usr/bin/env python3
"""Check a capture of Modbus TCP with Wireshark's own dissectors (mbtcp and modbus).

    check_mbtcp_capture.py FILE PORT [--json]

Runs `tshark -r FILE -d tcp.port==PORT,mbtcp -o mbtcp.tcp.port:PORT -T pdml`: the port is
not 502, so Modbus/TCP is named for it (`-d`), and the dissector's port preference (`-o`)
lets it tell requests (to PORT) from responses (from PORT); without it every PDU is
"Cannot classify packet type", an expert warning. Fails (exit 1, listing the frames)
when a frame with a TCP payload on that port shows a problem:

  not_dissected  the payload did not reach the mbtcp and modbus layers (and is not a
                 segment of a PDU reassembled in a later frame)
  malformed      tshark raised "Malformed Packet" (`_ws.malformed`)
  expert         an expert info of severity warning or error in the mbtcp or modbus
                 layers or a `_ws.*` layer
  leftover       payload bytes no dissector took (a raw "data" layer), or octets at the
                 end of a Modbus PDU that no field of the modbus layer covers (the
                 dissector passes over them silently)

Prints a report: frames with a payload, Modbus/TCP PDUs, requests and responses by
function code (decimal, as tshark shows `modbus.func_code`, without the exception bit),
exception responses by function code and exception code, responses Wireshark matched to
their request (`modbus.request_frame`), and the problems. Exit 0 clean, 1 problems or no
Modbus/TCP PDU at all, 2 tshark missing or failed.
"""

import argparse
import collections
import json
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

LAYERS = {"mbtcp", "modbus"}
WARNING = 6291456  # _ws.expert.severity: PI_WARN; PI_ERROR (8388608) is above it


def fields(element, name):
    return [field.get("show") for field in element.iter("field") if field.get("name") == name]


def first(element, name, default=None):
    return next(iter(fields(element, name)), default)


def unconsumed(proto):
    """Octets at the end of a layer that none of its fields covers: the modbus dissector
    passes over octets after what a function code defines without a word."""
    start, size = int(proto.get("pos", "0")), int(proto.get("size", "0"))
    end = start
    for field in proto.iter("field"):
        length = int(field.get("size", "0") or "0")
        if length:
            end = max(end, int(field.get("pos", "0")) + length)
    return max(0, start + size - end)


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("file")
    parser.add_argument("port", type=int)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if shutil.which("tshark") is None:
        print("tshark not installed", file=sys.stderr)
        return 2
    run = subprocess.run(
        [
            "tshark",
            "-r",
            args.file,
            "-d",
            f"tcp.port=={args.port},mbtcp",
            "-o",
            f"mbtcp.tcp.port:{args.port}",
            "-T",
            "pdml",
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    if run.returncode != 0:
        print(f"tshark failed: {run.stderr}", file=sys.stderr)
        return 2
    root = ET.fromstring(run.stdout)
    problems = []
    frames = 0
    pdus = 0
    requests = collections.Counter()
    responses = collections.Counter()
    exceptions = collections.Counter()
    matched = 0
    for packet in root.iter("packet"):
        protos = packet.findall("proto")
        names = [proto.get("name") for proto in protos]
        number = first(packet, "num", "?")
        tcp = next((proto for proto in protos if proto.get("name") == "tcp"), None)
        if tcp is None:
            continue
        if int(first(tcp, "tcp.len", "0")) == 0:
            continue
        frames += 1
        source = int(first(tcp, "tcp.srcport", "0"))
        destination = int(first(tcp, "tcp.dstport", "0"))
        if args.port not in (source, destination):
            continue
        if "mbtcp" not in names or "modbus" not in names:
            if not fields(tcp, "tcp.reassembled_in"):
                problems.append((number, "not_dissected", ":".join(names)))
        direction = requests if destination == args.port else responses
        for proto in protos:
            name = proto.get("name")
            if name == "mbtcp":
                pdus += 1
            if name == "modbus":
                code = first(proto, "modbus.func_code", "?")
                direction[code] += 1
                exception = first(proto, "modbus.exception_code")
                if exception is not None:
                    if direction is requests:
                        problems.append((number, "expert", "an exception code in a request"))
                    exceptions[f"{code}/{exception}"] += 1
                if fields(proto, "modbus.request_frame"):
                    matched += 1
                unread = unconsumed(proto)
                if unread:
                    problems.append((number, "leftover", f"{unread} octets of the PDU not dissected"))
            if name in ("_ws.malformed", "malformed"):
                problems.append((number, "malformed", proto.get("showname", "")))
            if name == "data":
                problems.append((number, "leftover", proto.get("showname", "")))
            if name in LAYERS or name.startswith("_ws."):
                for expert in proto.iter("field"):
                    if expert.get("name") != "_ws.expert":
                        continue
                    if int(first(expert, "_ws.expert.severity", "0")) >= WARNING:
                        message = first(expert, "_ws.expert.message", expert.get("showname"))
                        problems.append((number, "expert", f"{name}: {message}"))

    def counted(counter):
        """Function codes in numeric order (`3`, `15`, `3/2`)."""
        order = lambda item: [int(part) if part.isdigit() else part for part in item[0].split("/")]
        return dict(sorted(counter.items(), key=order))

    report = {
        "frames": frames,
        "mbtcp": pdus,
        "requests": counted(requests),
        "responses": counted(responses),
        "exceptions": counted(exceptions),
        "matched_responses": matched,
        "problems": [{"frame": n, "kind": k, "detail": d} for n, k, d in problems],
    }
    if args.json:
        print(json.dumps(report))
    else:
        print(
            f"{frames} frames, {pdus} Modbus/TCP PDUs, requests {report['requests']}, "
            f"responses {report['responses']}, exceptions {report['exceptions']}, "
            f"{matched} responses matched, {len(problems)} problems"
        )
        for number, kind, detail in problems[:50]:
            print(f"  frame {number}: {kind} {detail}")
    if problems or pdus == 0:
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
