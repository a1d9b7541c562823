#!/usr/bin/env python3
"""Check a capture of IEC 60870-5-101 or -103 carried over TCP with tshark's dissectors.

    check_capture_ft12.py FILE PORT --protocol iec60870_101|iec60870_5_103
                          [--expect-asdus N] [--json]

Runs `tshark -r FILE -d tcp.port==PORT,PROTOCOL -T pdml` and fails (exit 1, listing
the frames) when a frame with a TCP payload on that port shows a problem:

  not_dissected  the payload was not given to the protocol (no PROTOCOL layer)
  malformed      tshark raised "Malformed Packet"
  expert         an expert info of severity warning or error in the FT1.2/ASDU layers
  leftover       payload bytes the dissector left as raw "data"

Prints frame and ASDU counts (per type id for 101, per ASDU type for 103). Exit 0
clean, 1 problems (or fewer ASDUs than --expect-asdus), 2 usage error or tshark failed.
"""

import argparse
import collections
import json
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

LAYERS = {"iec60870_101", "iec60870_5_103", "iec60870_asdu"}


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("file")
    parser.add_argument("port", type=int)
    parser.add_argument("--protocol", required=True, choices=["iec60870_101", "iec60870_5_103"])
    parser.add_argument("--expect-asdus", type=int, default=1)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if shutil.which("tshark") is None:
        print("tshark not installed", file=sys.stderr)
        return 2
    run = subprocess.run(
        ["tshark", "-r", args.file, "-d", f"tcp.port=={args.port},{args.protocol}", "-T", "pdml"],
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
    asdus = collections.Counter()
    for packet in root.iter("packet"):
        protos = {proto.get("name"): proto for proto in packet.findall("proto")}
        number = next(
            (f.get("show") for f in packet.iter("field") if f.get("name") == "num"), "?"
        )
        tcp = protos.get("tcp")
        if tcp is None:
            continue
        length = next(
            (int(f.get("show")) for f in tcp.iter("field") if f.get("name") == "tcp.len"), 0
        )
        if length == 0:
            continue
        frames += 1
        if args.protocol not in protos:
            problems.append((number, "not_dissected", ", ".join(protos)))
            continue
        if "_ws.malformed" in protos or "malformed" in protos:
            problems.append((number, "malformed", ""))
        if "data" in protos:
            problems.append((number, "leftover", protos["data"].get("showname", "")))
        for name, proto in protos.items():
            if name not in LAYERS and name != "_ws.expert":
                continue
            for field in proto.iter("field"):
                if field.get("name") == "_ws.expert.severity" and field.get("show") in (
                    "6291456",  # warning
                    "8388608",  # error
                ):
                    problems.append((number, "expert", proto.get("showname", name)))
        for field in packet.iter("field"):
            name = field.get("name")
            if name in (
                "iec60870_asdu.typeid",
                "iec60870_5_103.asdu_typeid_mon",
                "iec60870_5_103.asdu_typeid_ctrl",
            ):
                asdus[field.get("show")] += 1
    report = {
        "protocol": args.protocol,
        "frames": frames,
        "asdus": sum(asdus.values()),
        "types": dict(sorted(asdus.items())),
        "problems": [{"frame": n, "kind": k, "detail": d} for n, k, d in problems],
    }
    if args.json:
        print(json.dumps(report))
    else:
        print(
            f"{args.protocol}: {frames} frames, {report['asdus']} ASDUs {report['types']}, "
            f"{len(problems)} problems"
        )
        for number, kind, detail in problems[:50]:
            print(f"  frame {number}: {kind} {detail}")
    if problems or report["asdus"] < args.expect_asdus:
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
