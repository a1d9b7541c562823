#!/usr/bin/env python3
"""python-snap7's S7 client against a server of the s7 crate's interoperability tests.

    snap7_client.py --port N [--host 127.0.0.1] [--rack 0] [--slot 1]
                    [--connection-type 1] [--timeout 20] CALLS

Connects with snap7.client.Client.connect(host, rack, slot, port) (connection type 1 PG
by default, as snap7 sends it; 2 OP, 3 S7 basic), then makes the client calls of CALLS, a
JSON list, in order, each whatever it raises:

    [{"call": "db_read", "args": [1, 0, 8]},
     {"call": "db_write", "args": [1, 10, {"hex": "0102"}]},
     {"call": "read_area", "args": [{"area": "MK"}, 0, 4, 2]},
     {"call": "read_area", "args": [{"area": "DB"}, 1, 3, 1, {"word_len": "Bit"}]},
     {"call": "read_multi_vars", "args": [[{"area": {"area": "DB"}, "db_number": 1, "start": 0, "size": 2}]]}]

Arguments: {"hex": ...} is a bytearray, {"area": NAME} a snap7.type.Area (PE, PA, MK, DB),
{"word_len": NAME} a snap7.type.WordLen (Bit, Byte, Word, Int, DWord, DInt, Real), inside
lists and dicts too. Prints one JSON object a line, flushed:

    {"event": "connected", "pdu_length": 240, "snap7": "3.3.0"}
    {"call": "db_read", "ok": true, "result": {"hex": "0000..."}}
    {"call": "db_read", "ok": false, "error": "S7ProtocolError: ..."}
    {"event": "error", "message": "connect failed: ..."}

Results: a bytearray as {"hex": ...}, lists and tuples element by element, numbers and
booleans as they are, anything else as its repr. Exit 0 after the calls (whatever their
results), 2 when it cannot connect or on bad usage.
"""

import argparse
import json
import signal
import sys

import snap7
from snap7.type import Area, WordLen


def emit(**fields):
    print(json.dumps(fields), flush=True)


def argument(value):
    if isinstance(value, list):
        return [argument(item) for item in value]
    if isinstance(value, dict):
        if set(value) == {"hex"}:
            return bytearray.fromhex(value["hex"])
        if set(value) == {"area"} and isinstance(value["area"], str):
            return Area[value["area"]]
        if set(value) == {"word_len"}:
            return WordLen[value["word_len"]]
        return {key: argument(item) for key, item in value.items()}
    return value


def result(value):
    if isinstance(value, (bytes, bytearray)):
        return {"hex": bytes(value).hex()}
    if isinstance(value, (list, tuple)):
        return [result(item) for item in value]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return repr(value)


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--rack", type=int, default=0)
    parser.add_argument("--slot", type=int, default=1)
    parser.add_argument("--connection-type", type=int, default=1)
    parser.add_argument("--timeout", type=int, default=20, help="seconds for everything")
    parser.add_argument("calls")
    args = parser.parse_args()
    calls = json.loads(args.calls)

    # A bound on the whole run: a hung peer ends the script, not the test.
    signal.signal(signal.SIGALRM, lambda *_: (emit(event="error", message="timeout"), sys.exit(3)))
    signal.alarm(args.timeout)

    client = snap7.client.Client()
    client.set_connection_type(args.connection_type)
    try:
        client.connect(args.host, args.rack, args.slot, args.port)
    except Exception as error:  # noqa: BLE001 - reported to the test
        emit(event="error", message=f"connect failed: {type(error).__name__}: {error}")
        return 2
    emit(event="connected", pdu_length=client.get_pdu_length(), snap7=snap7.__version__)
    for call in calls:
        name = call["call"]
        try:
            value = getattr(client, name)(*argument(call.get("args", [])))
            emit(call=name, ok=True, result=result(value))
        except Exception as error:  # noqa: BLE001 - each call's outcome is the test's data
            emit(call=name, ok=False, error=f"{type(error).__name__}: {error}")
    client.disconnect()
    return 0


if __name__ == "__main__":
    sys.exit(main())
