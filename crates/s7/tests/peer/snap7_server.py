#!/usr/bin/env python3
"""python-snap7's S7 server as the PLC of the s7 crate's interoperability tests.

    snap7_server.py [--host 127.0.0.1] [--port 0] [--db N:SIZE]... [--area-size 64]
                    [--fill AREA:START:HEX]...

Registers data blocks (--db), process inputs PE (I), process outputs PA (Q) and markers
MK (M) of --area-size bytes, all zeroed, then writes the --fill bytes (AREA is DB<n>, I, Q
or M; START a byte number; HEX the bytes). Port 0 takes a free port. Prints one JSON object
a line on stdout, flushed:

    {"event": "ready", "host": "127.0.0.1", "port": 40123, "snap7": "3.3.0"}
    {"event": "dump", "areas": {"DB1": "00ff...", "I": "...", "Q": "...", "M": "..."}}
    {"event": "error", "message": "..."}

Standard input takes one command a line: `dump` (the line above, every area's bytes as
they are now), `quit`. End of input and SIGTERM stop it too. Exit 0, 2 on bad usage or
when the server cannot start.
"""

import argparse
import json
import logging
import signal
import sys
import threading

import snap7
from snap7.type import SrvArea


def emit(**fields):
    print(json.dumps(fields), flush=True)


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=0)
    parser.add_argument("--db", action="append", default=[], metavar="N:SIZE")
    parser.add_argument("--area-size", type=int, default=64)
    parser.add_argument("--fill", action="append", default=[], metavar="AREA:START:HEX")
    args = parser.parse_args()

    areas = {
        "I": (SrvArea.PE, 0, bytearray(args.area_size)),
        "Q": (SrvArea.PA, 0, bytearray(args.area_size)),
        "M": (SrvArea.MK, 0, bytearray(args.area_size)),
    }
    for spec in args.db:
        number, size = (int(part) for part in spec.split(":"))
        areas[f"DB{number}"] = (SrvArea.DB, number, bytearray(size))
    for spec in args.fill:
        name, start, data = spec.split(":")
        memory = areas[name.upper()][2]
        data = bytes.fromhex(data)
        memory[int(start) : int(start) + len(data)] = data

    # The refusals the tests provoke (unknown data blocks, ranges) are logged by snap7 as
    # warnings; the answers on the wire are what the tests look at.
    logging.getLogger("snap7").setLevel(logging.ERROR)
    server = snap7.server.Server(log=False)
    for area, index, memory in areas.values():
        server.register_area(area, index, memory)
    server.host = args.host
    try:
        server.start(tcp_port=args.port)
    except Exception as error:  # noqa: BLE001 - reported to the test
        emit(event="error", message=f"server start failed: {error}")
        return 2
    port = server.server_socket.getsockname()[1]
    emit(event="ready", host=args.host, port=port, snap7=snap7.__version__)

    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())

    def console():
        for line in sys.stdin:
            command = line.strip()
            if command == "dump":
                emit(event="dump", areas={name: memory.hex() for name, (_, _, memory) in areas.items()})
            elif command == "quit":
                break
            elif command:
                emit(event="error", message=f"unknown command {command!r}")
        stop.set()

    threading.Thread(target=console, daemon=True).start()
    stop.wait()
    server.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
