"""Watches a mission served live (`crackbot run --foxglove ADDR`) as the Foxglove app would: a
client of the Foxglove WebSocket protocol (the `websockets` package, not the robot's code) that
subscribes to the tactile and verdict channels and counts what arrives.

    python scripts/foxglove_live_check.py ws://127.0.0.1:8765 [--seconds 60] [--until-verdicts 1]

It retries the connection until the server is up (the mission starts it after its rig), then
prints one JSON line: the channels advertised (topic → schema name) and the messages received
per subscribed topic, with the first tactile sample decoded. Exits 1 when nothing arrived.
"""

import argparse
import asyncio
import json
import struct
import sys
import time

import websockets

SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
WANTED = ("/tactile", "/slide", "/verdicts")


async def watch(url, seconds, until_verdicts):
    deadline = time.monotonic() + seconds
    while True:
        try:
            ws = await websockets.connect(url, subprotocols=SUBPROTOCOLS, max_size=None)
            break
        except OSError:
            if time.monotonic() > deadline:
                raise
            await asyncio.sleep(0.1)
    advertised, subscribed, counts, first = {}, {}, {}, {}
    async with ws:
        while time.monotonic() < deadline:
            try:
                raw = await asyncio.wait_for(ws.recv(), timeout=max(0.1, deadline - time.monotonic()))
            except (asyncio.TimeoutError, websockets.ConnectionClosed):
                break
            if isinstance(raw, str):
                msg = json.loads(raw)
                if msg.get("op") == "advertise":
                    subs = []
                    for c in msg["channels"]:
                        advertised[c["topic"]] = c.get("schemaName")
                        if c["topic"] in WANTED:
                            sid = len(subscribed) + 1
                            subscribed[sid] = c["topic"]
                            subs.append({"id": sid, "channelId": c["id"]})
                    if subs:
                        await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
                continue
            if raw[0] != 1:  # MessageData: opcode, subscription id (u32), log time (u64), payload
                continue
            sid, log_time = struct.unpack_from("<IQ", raw, 1)
            topic = subscribed.get(sid)
            if topic is None:
                continue
            counts[topic] = counts.get(topic, 0) + 1
            if topic not in first:
                first[topic] = {"log_time_ns": log_time, "message": json.loads(raw[13:])}
            if counts.get("/verdicts", 0) >= until_verdicts and counts.get("/tactile", 0) > 0:
                break
    return {"advertised": advertised, "received": counts, "first": first}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("url")
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--until-verdicts", type=int, default=1)
    args = ap.parse_args()
    result = asyncio.run(watch(args.url, args.seconds, args.until_verdicts))
    print(json.dumps(result))
    sys.exit(0 if result["received"] else 1)


if __name__ == "__main__":
    main()
