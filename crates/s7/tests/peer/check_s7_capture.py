#!/usr/bin/env python3
"""Check a capture of S7 over ISO-on-TCP with Wireshark's own dissectors.

    check_s7_capture.py FILE PORT [--json]

Runs `tshark -r FILE -d tcp.port==PORT,tpkt -T pdml` (the port is not 102, so TPKT is
named for it; COTP and S7comm follow by themselves) and fails (exit 1, listing the frames)
when a frame with a TCP payload on that port shows a problem:

  not_dissected  the payload did not reach TPKT and COTP, or a COTP data TPDU not S7comm
  malformed      tshark raised "Malformed Packet"
  expert         an expert info of severity warning or error in the TPKT, COTP or S7comm layers
  leftover       payload bytes no dissector took (a raw "data" layer)

Prints a report: frames with a payload, TPKT frames, COTP TPDU types, S7comm PDUs by ROSCTR,
functions (by their hex code), item return codes and the problems. Exit 0 clean, 1 problems
or no S7comm PDU at all, 2 tshark missing or failed.
"""

import argparse
import collections
import json
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

LAYERS = {"tpkt", "cotp", "s7comm"}
COTP_DATA = "0x0f"  # the DT TPDU type as tshark shows cotp.type


def fields(element, name):
    return [field.get("show") for field in element.iter("field") if field.get("name") == name]


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
        ["tshark", "-r", args.file, "-d", f"tcp.port=={args.port},tpkt", "-T", "pdml"],
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
    tpkt_frames = 0
    cotp_types = collections.Counter()
    rosctr = collections.Counter()
    functions = collections.Counter()
    return_codes = collections.Counter()
    s7_pdus = 0
    for packet in root.iter("packet"):
        protos = packet.findall("proto")
        names = [proto.get("name") for proto in protos]
        number = next(iter(fields(packet, "num")), "?")
        tcp = next((proto for proto in protos if proto.get("name") == "tcp"), None)
        if tcp is None:
            continue
        length = int(next(iter(fields(tcp, "tcp.len")), "0"))
        if length == 0:
            continue
        frames += 1
        if "tpkt" not in names or "cotp" not in names:
            problems.append((number, "not_dissected", ", ".join(names)))
            continue
        tpkt_frames += names.count("tpkt")
        for proto in protos:
            name = proto.get("name")
            if name == "cotp":
                types = fields(proto, "cotp.type")
                cotp_types.update(types)
                if COTP_DATA in types and "s7comm" not in names:
                    problems.append((number, "not_dissected", "COTP data without S7comm"))
            if name == "s7comm":
                s7_pdus += 1
                rosctr.update(fields(proto, "s7comm.header.rosctr"))
                functions.update(fields(proto, "s7comm.param.func"))
                return_codes.update(fields(proto, "s7comm.data.returncode"))
            if name in ("_ws.malformed", "malformed"):
                problems.append((number, "malformed", proto.get("showname", "")))
            if name == "data":
                problems.append((number, "leftover", proto.get("showname", "")))
            if name in LAYERS or name == "_ws.expert":
                for field in proto.iter("field"):
                    if field.get("name") == "_ws.expert.severity" and field.get("show") in (
                        "6291456",  # warning
                        "8388608",  # error
                    ):
                        problems.append((number, "expert", proto.get("showname", name)))
    report = {
        "frames": frames,
        "tpkt": tpkt_frames,
        "s7comm": s7_pdus,
        "cotp_types": dict(sorted(cotp_types.items())),
        "rosctr": dict(sorted(rosctr.items())),
        "functions": dict(sorted(functions.items())),
        "return_codes": dict(sorted(return_codes.items())),
        "problems": [{"frame": n, "kind": k, "detail": d} for n, k, d in problems],
    }
    if args.json:
        print(json.dumps(report))
    else:
        print(
            f"{frames} frames, {tpkt_frames} TPKT, {s7_pdus} S7comm PDUs, rosctr {report['rosctr']}, "
            f"functions {report['functions']}, return codes {report['return_codes']}, "
            f"{len(problems)} problems"
        )
        for number, kind, detail in problems[:50]:
            print(f"  frame {number}: {kind} {detail}")
    if problems or s7_pdus == 0:
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
