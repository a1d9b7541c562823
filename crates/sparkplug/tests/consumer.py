#!/usr/bin/env python3
"""An independent Sparkplug B consumer for the tests: paho-mqtt and the published
protobuf of Eclipse Tahu (PyPI `tahu`, its sparkplug_b_pb2), nothing of ours.

Subscribes to spBv1.0/# on a broker and checks one edge node's session:
  * NBIRTH: seq 0, a bdSeq metric (Int64), Node Control/Rebirth (Boolean, false), every
    metric with a name, an alias and a datatype;
  * DBIRTH of each device of the node: after the NBIRTH, every metric with a name, an
    alias unique across the node and its devices, and a datatype;
  * NDATA and DDATA: one seq for all of the node's messages (NBIRTH 0, then DBIRTH,
    NDATA, DDATA) continuing modulo 256 without a gap, a payload timestamp, every metric
    by an alias of the node's birth (NDATA) or of that device's birth (DDATA), its value
    in the field of the birth's datatype, a timestamp; DDATA only of a device born and
    not dead since;
  * DDEATH: of a device born, with the next seq and a timestamp; the device says nothing
    more until its next DBIRTH;
  * NDEATH (the will): the bdSeq of the NBIRTH it closes.
Prints `READY` once subscribed, `DATA n` as data arrives, and at the end (NDEATH seen,
or the timeout) one JSON line: {"verdict": "PASS"|"FAIL", "problems": [...], ...} with
every value received as [name, timestamp, value, quality].

Usage: consumer.py PORT GROUP NODE MIN_DATA TIMEOUT_S
"""
import json
import sys
import threading
import time

import paho.mqtt.client as mqtt
from tahu import sparkplug_b_pb2 as sparkplug

port, group, node, min_data, timeout = (
    int(sys.argv[1]), sys.argv[2], sys.argv[3], int(sys.argv[4]), float(sys.argv[5]))
prefix = "spBv1.0/%s/" % group

INT_TYPES = {1, 2, 3, 5, 6, 7}
LONG_TYPES = {4, 8, 13}
FIELD = {9: "float_value", 10: "double_value", 11: "boolean_value", 12: "string_value", 14: "string_value"}
FIELD.update({t: "int_value" for t in INT_TYPES})
FIELD.update({t: "long_value" for t in LONG_TYPES})

problems = []
births = []          # bdSeq of each NBIRTH
deaths = []          # bdSeq of each NDEATH
aliases = {}         # alias -> (name, datatype, device or None)
values = []          # [name, timestamp, value, quality]
devices = set()      # devices born since the last NBIRTH and not dead since
device_deaths = []   # devices whose DDEATH came, in order
data_count = 0
next_seq = None
done = threading.Event()


def problem(text):
    problems.append(text)


def signed(value, datatype):
    bits = {1: 8, 2: 16, 3: 32, 4: 64}.get(datatype)
    if bits and value >= 1 << (bits - 1):
        value -= 1 << bits
    return value


def metric_value(metric, datatype):
    field = FIELD.get(datatype)
    if metric.is_null:
        return None
    if field is None:
        problem("metric %s: datatype %d unexpected" % (metric.name or metric.alias, datatype))
        return None
    if metric.WhichOneof("value") != field:
        problem("metric %s: value in %s, datatype %d wants %s" % (
            metric.name or metric.alias, metric.WhichOneof("value"), datatype, field))
        return None
    value = getattr(metric, field)
    if datatype in INT_TYPES or datatype in LONG_TYPES:
        value = signed(value, datatype)
    return value


def quality(metric):
    for key, value in zip(metric.properties.keys, metric.properties.values):
        if key == "Quality":
            return value.int_value
    return None


def on_connect(client, userdata, flags, reason_code, properties):
    client.subscribe("spBv1.0/#", qos=1)


def on_subscribe(client, userdata, mid, reason_codes, properties):
    print("READY", flush=True)


def next_in_sequence(kind, payload):
    """Checks a message's seq against the node's one sequence; False before any NBIRTH."""
    global next_seq
    if next_seq is None:
        problem("%s before NBIRTH" % kind)
        return False
    if payload.seq != next_seq:
        problem("%s seq %d, expected %d" % (kind, payload.seq, next_seq))
    next_seq = (payload.seq + 1) % 256
    return True


def on_message(client, userdata, message):
    global next_seq, data_count
    topic = message.topic
    if not topic.startswith(prefix):
        return
    parts = topic[len(prefix):].split("/")
    if len(parts) < 2 or parts[1] != node:
        return
    kind = parts[0]
    device = parts[2] if len(parts) > 2 else None
    payload = sparkplug.Payload()
    try:
        payload.ParseFromString(message.payload)
    except Exception as error:  # noqa: BLE001 - any decoding failure is a finding
        problem("%s: not a Sparkplug payload: %s" % (topic, error))
        return
    if kind == "NBIRTH":
        if payload.seq != 0:
            problem("NBIRTH seq %d, not 0" % payload.seq)
        by_name = {m.name: m for m in payload.metrics}
        bd = by_name.get("bdSeq")
        if bd is None or bd.datatype != 4:
            problem("NBIRTH without an Int64 bdSeq")
        rebirth = by_name.get("Node Control/Rebirth")
        if rebirth is None or rebirth.datatype != 11 or rebirth.boolean_value:
            problem("NBIRTH without Node Control/Rebirth Boolean false")
        births.append(bd.long_value if bd is not None else None)
        aliases.clear()
        devices.clear()
        for metric in payload.metrics:
            if not metric.name or not metric.HasField("alias") or not metric.HasField("datatype"):
                problem("NBIRTH metric without name, alias or datatype: %s" % metric)
                continue
            aliases[metric.alias] = (metric.name, metric.datatype, None)
            if metric.name not in ("bdSeq", "Node Control/Rebirth"):
                values.append([metric.name, metric.timestamp, metric_value(metric, metric.datatype), quality(metric)])
        next_seq = 1
    elif kind == "DBIRTH":
        if device is None:
            problem("DBIRTH without a device id: %s" % topic)
            return
        if not next_in_sequence(kind, payload):
            return
        devices.add(device)
        for metric in payload.metrics:
            if not metric.name or not metric.HasField("alias") or not metric.HasField("datatype"):
                problem("DBIRTH metric without name, alias or datatype: %s" % metric)
                continue
            if metric.alias in aliases and aliases[metric.alias][0] != metric.name:
                problem("DBIRTH %s: alias %d already %s" % (device, metric.alias, aliases[metric.alias][0]))
            aliases[metric.alias] = (metric.name, metric.datatype, device)
            values.append([metric.name, metric.timestamp, metric_value(metric, metric.datatype), quality(metric)])
    elif kind == "DDEATH":
        if device not in devices:
            problem("DDEATH of %s, not born" % device)
            return
        if not next_in_sequence(kind, payload):
            return
        if not payload.HasField("timestamp"):
            problem("DDEATH without timestamp")
        devices.discard(device)
        device_deaths.append(device)
    elif kind in ("NDATA", "DDATA"):
        if kind == "DDATA" and device not in devices:
            problem("DDATA of %s before its DBIRTH" % device)
            return
        if not next_in_sequence(kind, payload):
            return
        if not payload.HasField("timestamp"):
            problem("%s without timestamp" % kind)
        for metric in payload.metrics:
            if metric.alias not in aliases:
                problem("%s metric of unknown alias %d" % (kind, metric.alias))
                continue
            name, datatype, owner = aliases[metric.alias]
            if owner != device:
                problem("%s of %s carries %s, a metric of %s" % (kind, device or "the node", name, owner or "the node"))
            if not metric.HasField("timestamp"):
                problem("%s metric %s without timestamp" % (kind, name))
            values.append([name, metric.timestamp, metric_value(metric, datatype), quality(metric)])
        data_count += 1
        print("DATA %d" % data_count, flush=True)
    elif kind == "NDEATH":
        bd = [m for m in payload.metrics if m.name == "bdSeq"]
        deaths.append(bd[0].long_value if bd else None)
        done.set()


client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="tahu-consumer-%d" % port)
client.on_connect = on_connect
client.on_subscribe = on_subscribe
client.on_message = on_message
client.connect("127.0.0.1", port)
client.loop_start()
finished = done.wait(timeout)
client.loop_stop()
if not births:
    problem("no NBIRTH")
if data_count < min_data:
    problem("%d NDATA/DDATA, expected at least %d" % (data_count, min_data))
if not finished:
    problem("no NDEATH within %.0f s" % timeout)
elif births and deaths[-1] != births[-1]:
    problem("NDEATH bdSeq %s, the NBIRTH's %s" % (deaths[-1], births[-1]))
print(json.dumps({
    "verdict": "FAIL" if problems else "PASS",
    "problems": problems[:20],
    "births": births,
    "deaths": deaths,
    "data": data_count,
    "devices": sorted(devices),
    "device_deaths": device_deaths,
    "values": values,
}), flush=True)
