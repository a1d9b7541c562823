#!/usr/bin/env python3
"""hat-drivers' IEC 60870-5-103 master (an implementation that is not ours) on a
serial line, for interop tests against `stanice iec103 relay`.

    python3 tests/peer/hat103_master.py /dev/pts/N [--address 1]
        [--baud 9600] [--parity none|even] [--timeout 20]
        [--measurands 1] [--time-sync] [--command FUN,INF,on|off]
        [--wait-disturbance] [--verbose]

On the serial port PORT (8 data bits, 1 stop bit, parity --parity; a Linux
pseudo-terminal keeps no parity, so the default is none), in this order:
  1. opens the link to --address (hat's unbalanced master sends RESET of the
     remote link until the station acknowledges it) and polls class 1 (every
     second and on ACD) and class 2 (every 0.1 s),
  2. with --time-sync: clock synchronisation (ASDU 6, the host's local time),
  3. general interrogation of common address --address; waits for its
     termination (ASDU 8 with our scan number),
  4. waits until --measurands ASDUs 9 (measurands II) have arrived,
  5. with --command: a general command (ASDU 20) on FUN/INF, waits for its
     positive or negative confirmation (ASDU 1 with cause 20 / 21 and our
     return identifier as SIN) and then for the indication at the same FUN/INF
     with cause 12 (remote operation) and the commanded position,
  6. with --wait-disturbance: prints {"event":"waiting",...} and waits for an
     ASDU 23 (list of recorded disturbances; the relay sends one on its
     console's `fault`) and then one more ASDU 9, proof that hat decoded the
     23 and kept the connection,
  7. closes the line and exits.

Everything is bounded by --timeout seconds in total. One JSON object per line
on stdout, flushed:

  {"event":"ready","port":"/dev/pts/3","address":1,"hat_drivers":"0.10.10"}
  {"event":"connected","address":1}
  {"event":"time_sync_sent","seconds":0.02}
  {"event":"asdu","type":9,"vsq":9,"cause":2,"ca":1,"fun":1,"inf":148,"hex":"0909..."}
  {"event":"data","asdu":1,"cause":"GENERAL_INTERROGATION","ca":1,"fun":1,"inf":160,"value":"ON","sin":0}
  {"event":"data","asdu":9,"cause":"CYCLIC","ca":1,"fun":1,"inf":148,"values":[0.41,...],"invalid":[false,...],"overflow":[false,...]}
  {"event":"gi_done","seconds":0.31}
  {"event":"command","fun":1,"inf":160,"value":"OFF","success":true,"seconds":0.12}
  {"event":"feedback","fun":1,"inf":160,"value":"OFF","seconds":0.25}
  {"event":"waiting","for":"disturbance"}
  {"event":"data","asdu":2,"cause":"SPONTANEOUS","ca":1,"fun":160,"inf":92,"value":"ON","fault_number":1,"relative_time":40,"sin":0}
  {"event":"disturbance_seen","seconds":3.2}
  {"event":"done","asdus":14,"measurands":2}
  {"event":"error","reason":"timeout"|"disconnected"|"refused"|..., "message":"..."}

`asdu` is each ASDU as it came from the link layer, before hat decoded it: its
type, its raw VSQ octet (9 measurands with SQ = 0 is 9, with SQ = 1 it is 0x89)
and the octets in hex; the data lines are what hat's master made of it.

Exit status: 0 everything came; 1 timeout; 2 the connection dropped (hat closes
it on an ASDU it cannot decode); 3 the command was refused; 4 bad usage or the
port could not be opened.
"""

import argparse
import asyncio
import importlib.metadata
import json
import logging
import sys
import time

from hat.drivers import iec103
from hat.drivers import serial
from hat.drivers.iec60870 import link


def emit(obj):
    sys.stdout.write(json.dumps(obj, separators=(",", ":"), default=str) + "\n")
    sys.stdout.flush()


class Failure(Exception):
    def __init__(self, reason, message, status):
        super().__init__(message)
        self.reason = reason
        self.message = message
        self.status = status


class RawTap:
    """The link connection, passed to hat's master unchanged, printing every
    received ASDU's raw octets first."""

    def __init__(self, conn, on_asdu):
        self._conn = conn
        self._on_asdu = on_asdu
        self.count = 0

    @property
    def info(self):
        return self._conn.info

    @property
    def async_group(self):
        return self._conn.async_group

    @property
    def is_open(self):
        return self._conn.is_open

    async def send(self, data, **kwargs):
        await self._conn.send(data, **kwargs)

    async def receive(self):
        data = bytes(await self._conn.receive())
        self.count += 1
        line = {"event": "asdu", "hex": data.hex()}
        if len(data) >= 6:
            line.update(type=data[0], vsq=data[1], cause=data[2], ca=data[3],
                        fun=data[4], inf=data[5])
        emit(line)
        if data:
            self._on_asdu(data[0])
        return data

    def close(self):
        self._conn.close()

    async def async_close(self):
        await self._conn.async_close()


def cause_name(cause):
    return cause.name if hasattr(cause, "name") else cause


def parse_command(text):
    parts = text.split(",")
    if len(parts) != 3 or parts[2].lower() not in ("on", "off"):
        raise argparse.ArgumentTypeError("--command wants FUN,INF,on|off, got %r" % text)
    try:
        fun, inf = int(parts[0]), int(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError("FUN and INF are numbers: %r" % text)
    value = iec103.DoubleValue.ON if parts[2].lower() == "on" else iec103.DoubleValue.OFF
    return fun, inf, value


class Session:
    def __init__(self, args):
        self.args = args
        self.start = time.monotonic()
        self.measurands = 0
        self.measurand_event = asyncio.Event()
        self.feedback = None  # (fun, inf, value) awaited with cause REMOTE_OPERATION
        self.feedback_event = asyncio.Event()
        self.asdu_events = {}  # ASDU type -> Event, set when one arrives

    def arrived(self, asdu_type):
        self.asdu_events.setdefault(asdu_type, asyncio.Event()).set()

    async def wait_asdu(self, asdu_type):
        await self.asdu_events.setdefault(asdu_type, asyncio.Event()).wait()

    def seconds(self):
        return round(time.monotonic() - self.start, 3)

    def on_data(self, data):
        value = data.value
        line = {"event": "data", "cause": cause_name(data.cause), "ca": data.asdu_address,
                "fun": data.io_address.function_type,
                "inf": data.io_address.information_number}
        if isinstance(value, iec103.MeasurandValues):
            kinds = sorted(value.values, key=lambda kind: kind.value)
            asdu = kinds[0].value[0] if kinds else None
            items = [value.values[kind] for kind in kinds]
            line.update(asdu=asdu, values=[round(m.value, 6) for m in items],
                        invalid=[m.invalid for m in items],
                        overflow=[m.overflow for m in items])
            if asdu == 9:
                self.measurands += 1
                if self.measurands >= self.args.measurands:
                    self.measurand_event.set()
        elif isinstance(value, iec103.DoubleWithTimeValue):
            line.update(asdu=1, value=value.value.name, sin=value.supplementary,
                        invalid_time=value.time.invalid)
        elif isinstance(value, iec103.DoubleWithRelativeTimeValue):
            line.update(asdu=2, value=value.value.name, fault_number=value.fault_number,
                        relative_time=value.relative_time, sin=value.supplementary)
        else:
            line.update(asdu=None, value=repr(value))
        emit(line)
        if (self.feedback is not None
                and isinstance(value, iec103.DoubleWithTimeValue)
                and data.cause == iec103.DataCause.REMOTE_OPERATION
                and (data.io_address.function_type,
                     data.io_address.information_number) == self.feedback[:2]
                and value.value == self.feedback[2]):
            self.feedback_event.set()

    async def until(self, awaitable, master, what):
        """Awaits `awaitable`, failing when the connection closes first."""
        task = asyncio.ensure_future(awaitable)
        closing = asyncio.ensure_future(master.wait_closing())
        try:
            done, _ = await asyncio.wait({task, closing},
                                         return_when=asyncio.FIRST_COMPLETED)
            if task in done:
                return task.result()
            raise Failure("disconnected",
                          "the connection closed while waiting for %s" % what, 2)
        except ConnectionError:
            raise Failure("disconnected",
                          "the connection closed while waiting for %s" % what, 2)
        finally:
            for t in (task, closing):
                if not t.done():
                    t.cancel()

    async def run(self):
        args = self.args
        ca = args.address
        try:
            master_link = await link.create_master_link(
                port=args.port,
                address_size=link.AddressSize.ONE,
                baudrate=args.baud,
                bytesize=serial.ByteSize.EIGHTBITS,
                parity=serial.Parity.EVEN if args.parity == "even" else serial.Parity.NONE,
                stopbits=serial.StopBits.ONE)
        except Exception as error:
            raise Failure("open", "cannot open %s: %s" % (args.port, error), 4)
        emit({"event": "ready", "port": args.port, "address": ca,
              "hat_drivers": importlib.metadata.version("hat-drivers")})
        try:
            conn = await link_open(master_link, ca)
            emit({"event": "connected", "address": ca, "seconds": self.seconds()})
            tap = RawTap(conn, self.arrived)
            master = iec103.MasterConnection(tap, data_cb=self.on_data)
            try:
                await self.exchange(master, tap, ca)
            finally:
                await master.async_close()
        finally:
            await master_link.async_close()

    async def exchange(self, master, tap, ca):
        args = self.args
        if args.time_sync:
            # ASDU 6 to the relay's own common address (hat does not wait for
            # the relay's ASDU 6 answer: it only logs it).
            await self.until(master.time_sync(asdu_address=ca), master, "the clock sync")
            emit({"event": "time_sync_sent", "seconds": self.seconds()})
        started = time.monotonic()
        await self.until(master.interrogate(ca), master, "the GI termination")
        emit({"event": "gi_done", "seconds": round(time.monotonic() - started, 3)})

        await self.until(self.measurand_event.wait(), master,
                         "%d ASDU 9" % args.measurands)

        if args.command is not None:
            fun, inf, value = args.command
            self.feedback = (fun, inf, value)
            started = time.monotonic()
            success = await self.until(
                master.send_command(ca, iec103.IoAddress(fun, inf), value),
                master, "the command's confirmation")
            emit({"event": "command", "fun": fun, "inf": inf, "value": value.name,
                  "success": bool(success),
                  "seconds": round(time.monotonic() - started, 3)})
            if not success:
                raise Failure("refused", "the command was confirmed negatively", 3)
            await self.until(self.feedback_event.wait(), master,
                             "the position after the command")
            emit({"event": "feedback", "fun": fun, "inf": inf, "value": value.name,
                  "seconds": round(time.monotonic() - started, 3)})

        if args.wait_disturbance:
            # The relay's fault (typed on its console by whoever runs this):
            # ASDU 2 trips, then ASDU 23 announcing the new record; one more
            # ASDU 9 after it shows hat decoded the 23 and kept the connection.
            self.asdu_events.pop(9, None)
            self.asdu_events.pop(23, None)
            emit({"event": "waiting", "for": "disturbance"})
            await self.until(self.wait_asdu(23), master, "ASDU 23")
            self.asdu_events.pop(9, None)
            await self.until(self.wait_asdu(9), master, "an ASDU 9 after the ASDU 23")
            emit({"event": "disturbance_seen", "seconds": self.seconds()})

        if not master.is_open:
            raise Failure("disconnected", "the connection closed", 2)
        emit({"event": "done", "asdus": tap.count, "measurands": self.measurands})


async def link_open(master_link, address):
    # hat repeats RESET of the remote link until it is acknowledged (the
    # overall --timeout bounds it); class 1 on ACD or every second, class 2
    # every 0.1 s (the measurands are class 2 data).
    return await master_link.open_connection(
        address,
        response_timeout=1.0,
        send_retry_count=3,
        poll_class1_delay=1.0,
        poll_class2_delay=0.1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("port", help="serial port, e.g. the pty path the relay printed")
    parser.add_argument("--address", type=int, default=1,
                        help="link and common address of the relay (default 1)")
    parser.add_argument("--baud", type=int, default=9600)
    parser.add_argument("--parity", choices=("none", "even"), default="none",
                        help="none for a pseudo-terminal (it keeps no parity)")
    parser.add_argument("--timeout", type=float, default=20.0,
                        help="seconds for the whole exchange (default 20)")
    parser.add_argument("--measurands", type=int, default=1,
                        help="ASDUs 9 to wait for (default 1)")
    parser.add_argument("--command", type=parse_command, default=None,
                        metavar="FUN,INF,on|off",
                        help="a general command after the GI, e.g. 1,160,off")
    parser.add_argument("--time-sync", action="store_true",
                        help="synchronise the relay's clock (ASDU 6) before the GI")
    parser.add_argument("--wait-disturbance", action="store_true",
                        help="at the end, print a 'waiting' line and wait for an ASDU 23 "
                             "(list of recorded disturbances) and one more ASDU 9")
    parser.add_argument("--verbose", action="store_true",
                        help="hat's logs (every frame) on stderr")
    try:
        args = parser.parse_args()
    except SystemExit as error:
        sys.exit(4 if error.code else 0)

    logging.basicConfig(stream=sys.stderr,
                        level=logging.DEBUG if args.verbose else logging.WARNING,
                        format="%(asctime)s %(name)s %(levelname)s %(message)s")

    async def bounded():
        session = Session(args)
        try:
            await asyncio.wait_for(session.run(), args.timeout)
        except asyncio.TimeoutError:
            raise Failure("timeout", "no answer within %s s (%d ASDU 9 so far)"
                          % (args.timeout, session.measurands), 1)

    try:
        asyncio.run(bounded())
    except Failure as failure:
        emit({"event": "error", "reason": failure.reason, "message": failure.message})
        sys.exit(failure.status)
    except KeyboardInterrupt:
        sys.exit(1)


if __name__ == "__main__":
    main()
