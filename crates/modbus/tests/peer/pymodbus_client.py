#!/usr/bin/env python3
"""A pymodbus client for the interoperability tests of crates/modbus: runs every function
code the crate's servers carry out (1, 2, 3, 4, 5, 6, 15, 16, 23) and three requests a
server must refuse (exceptions 1, 2, 3) against one unit, over Modbus TCP or RTU on a
serial port (a pseudo-terminal's path, 19200 Bd 8N1), and prints what it got as one JSON
object. Exits 1 on an error it did not expect (no answer, a broken frame).

The server is expected to hold: discrete inputs 196..198 = 0,1,1; input registers
8..9 = 10, 11; everything else zero.
"""

import argparse
import json
import sys

from pymodbus import FramerType
from pymodbus.client import ModbusSerialClient, ModbusTcpClient
from pymodbus.pdu.register_message import ReadHoldingRegistersRequest


def checked(response, what):
    if response.isError():
        raise RuntimeError(f"{what}: {response}")
    return response


def exception_code(response):
    return getattr(response, "exception_code", None) if response.isError() else None


def main():
    parser = argparse.ArgumentParser()
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--tcp", metavar="HOST:PORT")
    where.add_argument("--serial", metavar="PATH")
    parser.add_argument("--unit", type=int, default=1)
    args = parser.parse_args()

    if args.tcp:
        host, port = args.tcp.rsplit(":", 1)
        client = ModbusTcpClient(host, port=int(port), timeout=5, retries=0)
    else:
        client = ModbusSerialClient(
            args.serial,
            framer=FramerType.RTU,
            baudrate=19200,
            bytesize=8,
            parity="N",
            stopbits=1,
            timeout=5,
            retries=0,
        )
    if not client.connect():
        print("cannot connect", file=sys.stderr)
        return 1
    unit = args.unit
    out = {}
    try:
        checked(client.write_coil(10, True, device_id=unit), "FC 5")
        checked(
            client.write_coils(20, [True, False, True, True, False, False, True, True, True], device_id=unit),
            "FC 15",
        )
        out["coil_10"] = checked(client.read_coils(10, count=1, device_id=unit), "FC 1").bits[:1]
        out["coils_19"] = checked(client.read_coils(19, count=11, device_id=unit), "FC 1").bits[:11]
        out["discrete_196"] = checked(
            client.read_discrete_inputs(196, count=3, device_id=unit), "FC 2"
        ).bits[:3]
        checked(client.write_register(100, 0xFFFF, device_id=unit), "FC 6")
        checked(client.write_registers(101, [1, 2, 0x8000], device_id=unit), "FC 16")
        out["holding_100"] = checked(
            client.read_holding_registers(100, count=4, device_id=unit), "FC 3"
        ).registers
        out["input_8"] = checked(client.read_input_registers(8, count=2, device_id=unit), "FC 4").registers
        out["read_write"] = checked(
            client.readwrite_registers(
                read_address=100, read_count=3, write_address=102, values=[7, 8], device_id=unit
            ),
            "FC 23",
        ).registers
        out["largest_read"] = len(
            checked(client.read_holding_registers(9875, count=125, device_id=unit), "FC 3").registers
        )
        out["exception_address"] = exception_code(
            client.read_holding_registers(9999, count=2, device_id=unit)
        )
        out["exception_function"] = exception_code(client.read_exception_status(device_id=unit))
        # pymodbus refuses to send 126 registers' read itself: its limit is lifted.
        too_many = ReadHoldingRegistersRequest(address=0, count=1, dev_id=unit)
        too_many.MAX_COUNT = 0xFFFF
        too_many.count = 126
        out["exception_value"] = exception_code(client.execute(False, too_many))
    except Exception as error:  # noqa: BLE001 - any failure is the test's message
        print(json.dumps(out), flush=True)
        print(f"error: {error}", file=sys.stderr)
        return 1
    finally:
        client.close()
    print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
