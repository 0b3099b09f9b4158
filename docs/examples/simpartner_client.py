#!/usr/bin/env python3
"""A minimal client of the SimPartner robot link, using only Python's standard library.

It connects to the robot (or to the stand-in `simpartner-robot`), authenticates by
answering the robot's CHALLENGE with an HMAC of the shared token (the token itself never
crosses the link), takes the control lease, drives forward (`drive 0.5 0`) for a few seconds
while sending keep-alives, prints telemetry and replies, then stops and gives the lease
back. docs/protocol.md describes every message used here.

    python3 docs/examples/simpartner_client.py --host 127.0.0.1 --port 47800 \\
        --token 00112233445566778899aabbccddeeff --seconds 3

Exit code 0 only if the robot welcomed us, gave us the lease, answered the drive
command `ok`, sent at least 10 TELEMETRY frames, and its x position increased.
"""

import argparse
import hashlib
import hmac
import select
import socket
import struct
import sys
import time
import zlib

# Message types (docs/protocol.md, "Messages").
HELLO, WELCOME, LEASE_ACQUIRE, LEASE_KEEPALIVE, LEASE_RELEASE, LEASE_STATE = 1, 2, 3, 4, 5, 6
COMMAND, REPLY, TELEMETRY, LASER, HEARTBEAT, ESTOP, REARM, EVENT, ERROR = 7, 8, 9, 10, 11, 12, 13, 14, 15
CHALLENGE, LIMITS = 16, 17
NAMES = {v: k for k, v in globals().items() if k.isupper() and isinstance(v, int)}

ROBOT_HEARTBEAT_BASE = 1 << 62   # the robot's heartbeats count from here; echo them unchanged
KEEPALIVE_PERIOD = 0.05          # [s] the robot stops 200 ms after the last keep-alive
MAX_PAYLOAD = 65524


# --- Frames: 'SP', version 1, type, payload length (uint32 LE), payload, CRC-32 (uint32 LE) ---

def encode(msg_type, fields=None):
    payload = "".join(f"{k}={v}\n" for k, v in (fields or {}).items()).encode("utf-8")
    header = b"SP" + bytes([1, msg_type]) + struct.pack("<I", len(payload))
    return header + payload + struct.pack("<I", zlib.crc32(header + payload))


class Decoder:
    """Splits the byte stream into (type, fields) messages; raises ValueError on a bad frame."""

    def __init__(self):
        self.buf = b""

    def feed(self, data):
        self.buf += data
        out = []
        while True:
            if len(self.buf) >= 2 and self.buf[:2] != b"SP":
                raise ValueError("bad magic")
            if len(self.buf) < 8:
                return out
            version, msg_type, length = self.buf[2], self.buf[3], struct.unpack_from("<I", self.buf, 4)[0]
            if version != 1:
                raise ValueError(f"unsupported version {version}")
            if length > MAX_PAYLOAD:
                raise ValueError(f"oversize payload {length}")
            if len(self.buf) < 12 + length:
                return out
            crc = struct.unpack_from("<I", self.buf, 8 + length)[0]
            if crc != zlib.crc32(self.buf[:8 + length]):
                raise ValueError("bad CRC")
            text = self.buf[8:8 + length].decode("utf-8")
            fields = dict(line.split("=", 1) for line in text.split("\n") if line)
            out.append((msg_type, fields))
            self.buf = self.buf[12 + length:]


def numbers(text):
    return [float(x) for x in text.split()]


class Client:
    def __init__(self, host, port, timeout):
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.decoder = Decoder()
        self.pending = []
        self.next_seq = 1
        self.heartbeats = 0

    def send(self, msg_type, fields=None):
        self.sock.sendall(encode(msg_type, fields))

    def command(self, text, expires_ms=500):
        seq = self.next_seq
        self.next_seq += 1
        self.send(COMMAND, {"seq": seq, "expires_ms": expires_ms, "command": text})
        return seq

    def poll(self, timeout):
        """Messages that arrive within `timeout` seconds (possibly none)."""
        if not self.pending:
            ready, _, _ = select.select([self.sock], [], [], max(0.0, timeout))
            if ready:
                data = self.sock.recv(65536)
                if not data:
                    raise ConnectionError("the robot closed the connection")
                self.pending.extend(self.decoder.feed(data))
        out, self.pending = self.pending, []
        for msg_type, fields in out:
            # Echo the robot's heartbeats so that it can measure the round trip.
            if msg_type == HEARTBEAT and int(fields["seq"]) >= ROBOT_HEARTBEAT_BASE:
                self.send(HEARTBEAT, fields)
        return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=47800)
    parser.add_argument("--token", required=True, help="the robot's shared secret, >= 32 hex digits")
    parser.add_argument("--seconds", type=float, default=3.0, help="how long to drive")
    parser.add_argument("--name", default="python-example")
    parser.add_argument("--print-every", type=int, default=5, help="print every N-th TELEMETRY frame")
    args = parser.parse_args()

    got = {"challenge": None, "welcome": False, "lease": False, "lease_granted": False, "drive_ok": False}
    telemetry = []   # (time, x, y) of every frame
    drive_seq = None

    def handle(msg_type, fields):
        nonlocal drive_seq
        if msg_type == CHALLENGE:
            got["challenge"] = fields["nonce"]
        elif msg_type == LIMITS:
            print(f"LIMITS drive_speed={fields.get('drive_speed', '-')} m/s "
                  f"articulation={fields.get('articulation', '-')} joints={len(fields['joints'].split())}")
        elif msg_type == WELCOME:
            got["welcome"] = True
            print(f"WELCOME robot={fields['robot']} session={fields['session']} "
                  f"telemetry_rate={fields['telemetry_rate']} Hz")
        elif msg_type == LEASE_STATE:
            got["lease"] = fields["yours"] == "1"
            got["lease_granted"] |= got["lease"]
            print(f"LEASE_STATE holder='{fields['holder']}' yours={fields['yours']}")
        elif msg_type == REPLY:
            print(f"REPLY seq={fields['seq']} status={fields['status']} {fields.get('reason', '')}".rstrip())
            if drive_seq is not None and int(fields["seq"]) == drive_seq and fields["status"] == "ok":
                got["drive_ok"] = True
        elif msg_type == TELEMETRY:
            t = float(fields["time"])
            x, y = numbers(fields["pose"])[:2]
            telemetry.append((t, x, y))
            if (len(telemetry) - 1) % args.print_every == 0:
                fl, fr, rl, rr = numbers(fields["wheel_normal"])
                print(f"TELEMETRY seq={fields['seq']} t={t:.3f} s  x={x:+.3f} y={y:+.3f} m  "
                      f"wheel normal FL {fl:.0f} FR {fr:.0f} RL {rl:.0f} RR {rr:.0f} N  "
                      f"rtt={float(fields['rtt_ms']):.2f} ms")
        elif msg_type in (EVENT, ERROR):
            print(f"{NAMES[msg_type]} {fields}")

    def pump(seconds, keepalive):
        """Handles messages for `seconds`, sending a keep-alive every 50 ms if asked."""
        end = time.monotonic() + seconds
        next_keepalive = time.monotonic()
        while True:
            now = time.monotonic()
            if now >= end:
                return
            if keepalive and now >= next_keepalive:
                client.send(LEASE_KEEPALIVE)
                next_keepalive += KEEPALIVE_PERIOD
            wait = min(end, next_keepalive if keepalive else end) - now
            for msg_type, fields in client.poll(wait):
                handle(msg_type, fields)

    def wait_for(condition, seconds, keepalive=False):
        end = time.monotonic() + seconds
        while not condition() and time.monotonic() < end:
            pump(min(0.05, end - time.monotonic()), keepalive)
        return condition()

    try:
        client = Client(args.host, args.port, timeout=5)
        # The robot speaks first: a CHALLENGE with a fresh nonce. HELLO answers it with
        # HMAC-SHA256(token, "simpartner-hello\n" nonce "\n" name "\n" role); nothing
        # else is served before it is accepted.
        if not wait_for(lambda: got["challenge"], 5):
            print("error: no CHALLENGE from the robot", file=sys.stderr)
            return 1
        text = f"simpartner-hello\n{got['challenge']}\n{args.name}\ncontrol".encode()
        proof = hmac.new(args.token.encode(), text, hashlib.sha256).hexdigest()
        client.send(HELLO, {"name": args.name, "role": "control", "proof": proof})
        if not wait_for(lambda: got["welcome"], 5):
            print("error: no WELCOME (wrong token?)", file=sys.stderr)
            return 1
        client.send(LEASE_ACQUIRE)
        if not wait_for(lambda: got["lease"], 5):
            print("error: the lease was not granted (another client holds it?)", file=sys.stderr)
            return 1
        wait_for(lambda: telemetry, 2, keepalive=True)
        drive_seq = client.command("drive 0.5 0")
        pump(args.seconds, keepalive=True)
        stop_seq = client.command("stop")
        print(f"sent stop (seq {stop_seq})")
        pump(0.3, keepalive=True)
        client.send(LEASE_RELEASE)
        wait_for(lambda: not got["lease"], 2)
        client.sock.close()
    except (OSError, ValueError, KeyError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1

    moved = telemetry[-1][1] - telemetry[0][1] if telemetry else 0.0
    print(f"{len(telemetry)} TELEMETRY frames; x moved {moved:+.3f} m")
    ok = got["welcome"] and got["lease_granted"] and got["drive_ok"] and len(telemetry) >= 10 and moved > 0
    if not got["drive_ok"]:
        print("error: the drive command was not answered ok", file=sys.stderr)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
