#!/usr/bin/env python3
"""Check a capture of IEC 60870-5-104 traffic with tshark's dissectors.

    check_capture.py FILE PORT [--json] [--allow-undecoded] [--allow-empty]
                               [--expect TYPE:N ...] [--max-list N]

Runs `tshark -r FILE -d tcp.port==PORT,iec60870_104` and fails (exit 1,
listing the frames) when any frame on that port shows a problem in the
IEC 104 layers:

  malformed      tshark raised "Malformed Packet" in a frame carrying IEC 104
  expert         an expert info of severity warning/error inside the
                 iec60870_104 / iec60870_asdu layers
  undissected    bytes in the 104 stream the dissector could not frame
                 (bad start octet 0x68, wrong length): "Data:" in the layer
  apdu_length    APDU length outside 4..253
  err_marker     the dissector's own "<ERR ...>" marker (e.g. unknown U
                 function, APDU length) in the packet summary
  unknown_type   a type identification IEC 60870-5-101/104 does not define
  unknown_cot    a cause of transmission that is not defined (0, 14..19, ...)
  undecoded      tshark showed the information objects only as "Raw Data"
                 (type it cannot decode); not fatal with --allow-undecoded
  incomplete     TCP payload that never became a complete APDU (capture ends
                 inside an APDU)

Also prints the number of APDUs per format (I/S/U), per U function, ASDUs
and information objects per type id, per cause of transmission and per
direction. With --json prints one JSON object instead of the text report.
Exit: 0 clean, 1 problems (or no IEC 104 APDU at all, unless
--allow-empty; or an --expect not met), 2 usage error / tshark failed.
"""

import argparse
import collections
import json
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

TYPE_NAMES = {
    1: "M_SP_NA_1", 2: "M_SP_TA_1", 3: "M_DP_NA_1", 4: "M_DP_TA_1",
    5: "M_ST_NA_1", 6: "M_ST_TA_1", 7: "M_BO_NA_1", 8: "M_BO_TA_1",
    9: "M_ME_NA_1", 10: "M_ME_TA_1", 11: "M_ME_NB_1", 12: "M_ME_TB_1",
    13: "M_ME_NC_1", 14: "M_ME_TC_1", 15: "M_IT_NA_1", 16: "M_IT_TA_1",
    17: "M_EP_TA_1", 18: "M_EP_TB_1", 19: "M_EP_TC_1", 20: "M_PS_NA_1",
    21: "M_ME_ND_1", 30: "M_SP_TB_1", 31: "M_DP_TB_1", 32: "M_ST_TB_1",
    33: "M_BO_TB_1", 34: "M_ME_TD_1", 35: "M_ME_TE_1", 36: "M_ME_TF_1",
    37: "M_IT_TB_1", 38: "M_EP_TD_1", 39: "M_EP_TE_1", 40: "M_EP_TF_1",
    41: "S_IT_TC_1",
    45: "C_SC_NA_1", 46: "C_DC_NA_1", 47: "C_RC_NA_1", 48: "C_SE_NA_1",
    49: "C_SE_NB_1", 50: "C_SE_NC_1", 51: "C_BO_NA_1",
    58: "C_SC_TA_1", 59: "C_DC_TA_1", 60: "C_RC_TA_1", 61: "C_SE_TA_1",
    62: "C_SE_TB_1", 63: "C_SE_TC_1", 64: "C_BO_TA_1",
    70: "M_EI_NA_1",
    81: "S_CH_NA_1", 82: "S_RP_NA_1", 83: "S_AR_NA_1", 84: "S_KR_NA_1",
    85: "S_KS_NA_1", 86: "S_KC_NA_1", 87: "S_ER_NA_1", 90: "S_US_NA_1",
    91: "S_UQ_NA_1", 92: "S_UR_NA_1", 93: "S_UK_NA_1", 94: "S_UA_NA_1",
    95: "S_UC_NA_1",
    100: "C_IC_NA_1", 101: "C_CI_NA_1", 102: "C_RD_NA_1", 103: "C_CS_NA_1",
    104: "C_TS_NA_1", 105: "C_RP_NA_1", 106: "C_CD_NA_1", 107: "C_TS_TA_1",
    110: "P_ME_NA_1", 111: "P_ME_NB_1", 112: "P_ME_NC_1", 113: "P_AC_NA_1",
    120: "F_FR_NA_1", 121: "F_SR_NA_1", 122: "F_SC_NA_1", 123: "F_LS_NA_1",
    124: "F_AF_NA_1", 125: "F_SG_NA_1", 126: "F_DR_TA_1", 127: "F_SC_NB_1",
}
COT_NAMES = {
    1: "per/cyc", 2: "back", 3: "spont", 4: "init", 5: "req", 6: "act",
    7: "actcon", 8: "deact", 9: "deactcon", 10: "actterm", 11: "retrem",
    12: "retloc", 13: "file",
    **{20 + i: ("inrogen" if i == 0 else "inro%d" % i) for i in range(17)},
    37: "reqcogen", 38: "reqco1", 39: "reqco2", 40: "reqco3", 41: "reqco4",
    44: "unknown_type", 45: "unknown_cot", 46: "unknown_ca", 47: "unknown_ioa",
}
U_FUNCS = {1: "STARTDT_act", 2: "STARTDT_con", 4: "STOPDT_act",
           8: "STOPDT_con", 16: "TESTFR_act", 32: "TESTFR_con"}
FRAME_FORMATS = {0: "I", 1: "S", 3: "U"}
SEV_WARNING = 0x00600000

FIELDS = [
    "frame.number", "tcp.srcport", "tcp.dstport", "tcp.len", "frame.protocols",
    "tcp.segment_data", "tcp.reassembled_in", "tcp.analysis.retransmission",
    "iec60870_104.type", "iec60870_104.utype", "iec60870_104.apdulen",
    "iec60870_104.data",
    "iec60870_asdu.typeid", "iec60870_asdu.causetx", "iec60870_asdu.numix",
    "iec60870_asdu.rawdata",
    "_ws.malformed", "_ws.expert.severity", "_ws.expert.message",
    "_ws.col.Info",  # last: free text
]
AGG = "\x1e"


def run_tshark(args, check=True):
    try:
        p = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           timeout=1800)
    except subprocess.TimeoutExpired:
        raise SystemExit("check_capture: tshark timed out")
    if check and p.returncode != 0:
        sys.stderr.write(p.stderr.decode(errors="replace"))
        raise SystemExit(2)
    return p.stdout.decode("utf-8", errors="replace")


def ints(s):
    out = []
    for x in s.split(AGG) if s else []:
        x = x.strip()
        if not x:
            continue
        try:
            out.append(int(x, 0))
        except ValueError:
            pass
    return out


def iec_expert_frames(tshark, path, decode_as, frames):
    """For frames with an expert info >= warning, find the ones whose expert
    sits inside an iec60870 layer (PDML pass over those frames only)."""
    if not frames:
        return {}
    found = {}
    frames = sorted(frames)
    for i in range(0, len(frames), 200):
        chunk = frames[i:i + 200]
        flt = "frame.number in {%s}" % " ".join(str(f) for f in chunk)
        xml = run_tshark([tshark, "-n", "-r", path, "-d", decode_as, "-Y", flt,
                          "-T", "pdml"])
        root = ET.fromstring(xml)
        for pkt in root.iter("packet"):
            num = None
            msgs = []
            for proto in pkt.findall("proto"):
                if proto.get("name") == "frame":
                    for f in proto.iter("field"):
                        if f.get("name") == "frame.number":
                            num = int(f.get("show"))
                            break
                name = proto.get("name", "")
                stack = [(proto, name)]
                while stack:
                    el, pname = stack.pop()
                    for child in el:
                        cname = child.get("name", "")
                        if child.tag == "proto":
                            stack.append((child, cname))
                            continue
                        if cname == "_ws.expert":
                            sev = 0
                            msg = child.get("showname") or child.get("show") or ""
                            for g in child.iter("field"):
                                if g.get("name") == "_ws.expert.severity":
                                    try:
                                        sev = int(g.get("value") or g.get("show"), 16)
                                    except (TypeError, ValueError):
                                        sev = 0
                                if g.get("name") == "_ws.expert.message":
                                    msg = g.get("show") or msg
                            if sev >= SEV_WARNING and pname.startswith("iec60870"):
                                msgs.append("%s: %s" % (pname, msg))
                        stack.append((child, pname))
            if num is not None and msgs:
                found[num] = msgs
    return found


def analyse(path, port, allow_undecoded=False):
    tshark = shutil.which("tshark")
    if not tshark:
        raise SystemExit("check_capture: tshark not found (bash scripts/install-test-deps.sh)")
    decode_as = "tcp.port==%d,iec60870_104" % port
    cmd = [tshark, "-n", "-r", path, "-d", decode_as,
           "-Y", "tcp.port==%d" % port, "-T", "fields",
           "-E", "separator=/t", "-E", "occurrence=a", "-E", "aggregator=" + AGG]
    for f in FIELDS:
        cmd += ["-e", f]
    out = run_tshark(cmd)

    problems = []  # (frame, kind, detail)
    counts = {
        "frames": 0, "frames_iec104": 0, "apdus": 0,
        "apdu_formats": collections.Counter(),
        "u_functions": collections.Counter(),
        "asdus_by_type": collections.Counter(),
        "objects_by_type": collections.Counter(),
        "asdus_by_cot": collections.Counter(),
        "apdus_to_port": 0, "apdus_from_port": 0,
        "tcp_retransmissions": 0,
    }
    expert_candidates = set()
    nfields = len(FIELDS)
    for line in out.split("\n"):  # not splitlines(): it splits on \x1e too
        if not line.strip():
            continue
        cols = line.split("\t", nfields - 1)
        cols += [""] * (nfields - len(cols))
        rec = dict(zip(FIELDS, cols))
        try:
            num = int(rec["frame.number"])
        except ValueError:
            continue
        counts["frames"] += 1
        protos = rec["frame.protocols"].split(":")
        has_iec = any(p.startswith("iec60870") for p in protos)
        info = rec["_ws.col.Info"].strip()
        if has_iec:
            counts["frames_iec104"] += 1
        formats = ints(rec["iec60870_104.type"])
        for fmt in formats:
            counts["apdus"] += 1
            counts["apdu_formats"][FRAME_FORMATS.get(fmt, "?%d" % fmt)] += 1
            if rec["tcp.srcport"] == str(port):
                counts["apdus_from_port"] += 1
            else:
                counts["apdus_to_port"] += 1
        for u in ints(rec["iec60870_104.utype"]):
            name = U_FUNCS.get(u)
            if name is None:
                problems.append((num, "err_marker", "unknown U function 0x%02x" % u))
                name = "0x%02x" % u
            counts["u_functions"][name] += 1
        for ln in ints(rec["iec60870_104.apdulen"]):
            if ln < 4 or ln > 253:
                problems.append((num, "apdu_length", "APDU length %d" % ln))
        if rec["iec60870_104.data"]:
            problems.append((num, "undissected",
                             "bytes not framed as APDU: %s" % rec["iec60870_104.data"].split(AGG)[0][:64]))
        typeids = ints(rec["iec60870_asdu.typeid"])
        numix = ints(rec["iec60870_asdu.numix"])
        for i, t in enumerate(typeids):
            name = TYPE_NAMES.get(t)
            if name is None:
                problems.append((num, "unknown_type", "type identification %d" % t))
                name = str(t)
            counts["asdus_by_type"][name] += 1
            if i < len(numix):
                counts["objects_by_type"][name] += numix[i]
        for c in ints(rec["iec60870_asdu.causetx"]):
            name = COT_NAMES.get(c)
            if name is None:
                problems.append((num, "unknown_cot", "cause of transmission %d" % c))
                name = str(c)
            counts["asdus_by_cot"][name] += 1
        if rec["iec60870_asdu.rawdata"]:
            problems.append((num, "undecoded",
                             "information objects not decoded by tshark (Raw Data)"))
        if rec["_ws.malformed"] and (has_iec or "IEC 60870" in rec["_ws.malformed"]):
            problems.append((num, "malformed", "Malformed Packet: %s" % info))
        elif "<ERR" in info:
            problems.append((num, "err_marker", info))
        sev = ints(rec["_ws.expert.severity"])
        if has_iec and sev and max(sev) >= SEV_WARNING and not rec["_ws.malformed"]:
            expert_candidates.add(num)
        if rec["tcp.analysis.retransmission"]:
            counts["tcp_retransmissions"] += 1
        elif rec["tcp.segment_data"] and not rec["tcp.reassembled_in"]:
            problems.append((num, "incomplete",
                             "TCP payload never completed an APDU: %s" % rec["tcp.segment_data"][:64]))

    for num, msgs in iec_expert_frames(tshark, path, decode_as, expert_candidates).items():
        for m in msgs:
            problems.append((num, "expert", m))

    # de-duplicate (same frame + kind + detail), keep order
    seen = set()
    uniq = []
    for p in sorted(problems, key=lambda x: x[0]):
        if p not in seen:
            seen.add(p)
            uniq.append(p)
    fatal = [p for p in uniq if not (allow_undecoded and p[1] == "undecoded")]
    return counts, uniq, fatal


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file")
    ap.add_argument("port", type=int)
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--allow-undecoded", action="store_true",
                    help="'undecoded' (Raw Data) findings do not fail the check")
    ap.add_argument("--allow-empty", action="store_true",
                    help="a capture without any IEC 104 APDU passes")
    ap.add_argument("--expect", action="append", default=[], metavar="TYPE:N",
                    help="require at least N ASDUs of TYPE (e.g. C_SC_NA_1:2); "
                         "TYPE may also be I, S, U or a U function like STARTDT_act")
    ap.add_argument("--max-list", type=int, default=50,
                    help="list at most this many problem lines")
    a = ap.parse_args(argv)
    if not os.path.isfile(a.file):
        print("check_capture: no such file: %s" % a.file, file=sys.stderr)
        return 2

    counts, problems, fatal = analyse(a.file, a.port, a.allow_undecoded)
    failures = []
    if fatal:
        failures.append("%d problem(s) in the IEC 104 layers" % len(fatal))
    if counts["apdus"] == 0 and not a.allow_empty:
        failures.append("no IEC 104 APDU on tcp port %d" % a.port)
    for e in a.expect:
        try:
            key, n = e.rsplit(":", 1)
            n = int(n)
        except ValueError:
            print("check_capture: bad --expect %r" % e, file=sys.stderr)
            return 2
        have = (counts["apdu_formats"].get(key) if key in ("I", "S", "U")
                else counts["u_functions"].get(key) if key in U_FUNCS.values()
                else counts["asdus_by_type"].get(key)) or 0
        if have < n:
            failures.append("expected >= %d %s, found %d" % (n, key, have))

    ok = not failures
    if a.json:
        out = {k: (dict(sorted(v.items())) if isinstance(v, collections.Counter) else v)
               for k, v in counts.items()}
        out.update({"file": a.file, "port": a.port, "ok": ok, "failures": failures,
                    "problems": [{"frame": f, "kind": k, "detail": d}
                                 for f, k, d in problems[:a.max_list]],
                    "problem_count": len(problems)})
        print(json.dumps(out, sort_keys=False))
    else:
        print("check_capture: %s (tcp port %d)" % (a.file, a.port))
        print("  frames on port: %d, with IEC 104: %d" % (counts["frames"], counts["frames_iec104"]))
        print("  APDUs: %d (to port %d: %d, from port %d: %d)" % (
            counts["apdus"], a.port, counts["apdus_to_port"], a.port, counts["apdus_from_port"]))
        if counts["tcp_retransmissions"]:
            print("  TCP retransmissions (not dissected again): %d" % counts["tcp_retransmissions"])
        print("  formats: " + ", ".join("%s=%d" % kv for kv in sorted(counts["apdu_formats"].items())))
        if counts["u_functions"]:
            print("  U functions: " + ", ".join("%s=%d" % kv for kv in sorted(counts["u_functions"].items())))
        if counts["asdus_by_type"]:
            print("  ASDUs per type id (objects):")
            for name, n in sorted(counts["asdus_by_type"].items()):
                print("    %-10s %7d  (%d)" % (name, n, counts["objects_by_type"].get(name, 0)))
        if counts["asdus_by_cot"]:
            print("  ASDUs per cause: " + ", ".join("%s=%d" % kv for kv in sorted(counts["asdus_by_cot"].items())))
        if problems:
            print("  problems (%d):" % len(problems))
            for f, k, d in problems[:a.max_list]:
                print("    frame %d: %s: %s" % (f, k, d))
            if len(problems) > a.max_list:
                print("    ... %d more" % (len(problems) - a.max_list))
        print("check_capture: %s" % ("OK" if ok else "FAIL: " + "; ".join(failures)))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
