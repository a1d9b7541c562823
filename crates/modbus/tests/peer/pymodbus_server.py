#!/usr/bin/env python3
"""A pymodbus server for the interoperability tests of crates/modbus: Modbus TCP on a
loopback port or RTU on a serial port (a pseudo-terminal's path, 19200 Bd 8N1).

One unit (--unit, default 1) with four separate tables of 10,000 entries, preset so that
a client can tell every table and address apart:

  coils            0..9: 1,0,1,1,0,0,1,1,1,0 (the rest 0)
  discrete inputs  0..7: 0,1,1,0,1,0,0,1
  holding          0..9: 100, 101, ..., 109
  input            0..3: 1000, 1001, 1002, 1003

Prints `ready` on a line of its own once it listens (or has the port open), then serves
until killed. Every write by a client is printed as a JSON line
{"table": "coils"|"holding", "address": N, "values": [...]}.
"""

import argparse
import asyncio
import json
import sys

from pymodbus import FramerType
from pymodbus.server import ModbusSerialServer, ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

SIZE = 10_000
COILS = [True, False, True, True, False, False, True, True, True, False]
DISCRETE = [False, True, True, False, True, False, False, True]
HOLDING = [100 + i for i in range(10)]
INPUT = [1000, 1001, 1002, 1003]


def bits(preset):
    return [SimData(0, values=preset + [False] * (SIZE - len(preset)), datatype=DataType.BITS)]


def registers(preset):
    return [SimData(0, values=preset + [0] * (SIZE - len(preset)), datatype=DataType.REGISTERS)]


def trace_pdu(sending, pdu):
    """Prints a client's writes as JSON lines (the request side, before execution)."""
    if not sending:
        code = pdu.function_code
        table = {5: "coils", 15: "coils", 6: "holding", 16: "holding", 23: "holding"}.get(code)
        if table:
            if code == 23:
                address, values = pdu.write_address, pdu.write_registers
            elif code in (5, 6):
                address, values = pdu.address, [pdu.bits[0]] if code == 5 else pdu.registers[:1]
            else:
                address = pdu.address
                values = pdu.bits[: pdu.count] if code == 15 else pdu.registers
            print(json.dumps({"table": table, "address": address, "values": list(values)}), flush=True)
    return pdu


async def main():
    parser = argparse.ArgumentParser()
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--tcp", type=int, metavar="PORT")
    where.add_argument("--serial", metavar="PATH")
    parser.add_argument("--unit", type=int, default=1)
    args = parser.parse_args()

    device = SimDevice(
        id=args.unit,
        simdata=(bits(COILS), bits(DISCRETE), registers(HOLDING), registers(INPUT)),
    )
    if args.tcp is not None:
        server = ModbusTcpServer(
            device, framer=FramerType.SOCKET, address=("127.0.0.1", args.tcp), trace_pdu=trace_pdu
        )
    else:
        server = ModbusSerialServer(
            device,
            framer=FramerType.RTU,
            port=args.serial,
            baudrate=19200,
            bytesize=8,
            parity="N",
            stopbits=1,
            trace_pdu=trace_pdu,
        )
    await server.serve_forever(background=True)
    print("ready", flush=True)
    await server.serving


if __name__ == "__main__":
    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        sys.exit(0)
