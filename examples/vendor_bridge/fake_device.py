#!/usr/bin/env python3
"""A device server for the rigidtouch UDP device protocol, version 1, in plain Python.

It simulates a hand that taps downwards along -z and streams its state to the renderer that last
sent it a command; the newest command's force pushes back on the simulated hand. Use it as a
template for an SDK with Python bindings: replace read_device() and write_device().
See docs/device-protocol.md. Python's sleep is not a real-time clock: expect jitter.

    python3 fake_device.py --listen 127.0.0.1:47000 --rate 1000
"""
import argparse, math, socket, struct, time, zlib

MAGIC, VERSION, STATE, COMMAND = 0x48435452, 1, 1, 2
STATE_PAYLOAD = struct.Struct("<Q14dI")   # sequence, time, p(3), q(4 wxyz), v(3), w(3), buttons
COMMAND_PAYLOAD = struct.Struct("<Q6dI")  # sequence, force(3), torque(3), flags


def packet(kind, payload):
    head = struct.pack("<IHHI", MAGIC, VERSION, kind, len(payload))
    return head + struct.pack("<I", zlib.crc32(payload, zlib.crc32(head))) + payload


def decode_command(data):
    if len(data) != 16 + COMMAND_PAYLOAD.size:
        return None
    magic, version, kind, size, crc = struct.unpack_from("<IHHII", data)
    if (magic, version, kind, size) != (MAGIC, VERSION, COMMAND, COMMAND_PAYLOAD.size):
        return None
    if crc != zlib.crc32(data[16:], zlib.crc32(data[:12])):
        return None
    sequence, fx, fy, fz, tx, ty, tz, flags = COMMAND_PAYLOAD.unpack_from(data, 16)
    if not all(math.isfinite(v) for v in (fx, fy, fz, tx, ty, tz)):
        return None
    return sequence, (fx, fy, fz)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--listen", default="127.0.0.1:47000")
    parser.add_argument("--rate", type=float, default=1000.0, help="Hz")
    parser.add_argument("--watchdog", type=float, default=0.05, help="s")
    parser.add_argument("--duration", type=float, default=0.0, help="s, 0 = until Ctrl-C")
    args = parser.parse_args()
    host, port = args.listen.rsplit(":", 1)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind((host, int(port)))
    sock.setblocking(False)

    h, mass_kg, z_m, vz_mps = 1.0 / args.rate, 0.1, 0.05, 0.0
    client, sequence, newest, force_N, fresh_at = None, 0, -1, (0.0, 0.0, 0.0), -1.0
    start = time.monotonic()
    tick = 0
    while args.duration <= 0 or time.monotonic() - start < args.duration:
        now = time.monotonic()
        if client is not None:  # 1. read the device (here: simulate it) and send its state
            sequence += 1
            state = (sequence, now - start, 0.0, 0.0, z_m, 1.0, 0.0, 0.0, 0.0,
                     0.0, 0.0, vz_mps, 0.0, 0.0, 0.0, 0)
            sock.sendto(packet(STATE, STATE_PAYLOAD.pack(*state)), client)
        while True:  # 2. drain commands, newest sequence wins
            try:
                data, source = sock.recvfrom(512)
            except BlockingIOError:
                break
            command = decode_command(data)
            if command is None:
                continue
            if source != client:
                client, newest = source, -1
            if command[0] >= newest:
                newest, force_N, fresh_at = command[0], command[1], now
        # 3. display the force, or zero when the watchdog has tripped
        shown = force_N if now - fresh_at <= args.watchdog else (0.0, 0.0, 0.0)
        hand_N = -0.5 if math.sin(2.0 * math.pi * 1.0 * (now - start)) > 0 else 0.3
        vz_mps += h * (hand_N + shown[2]) / mass_kg - h * 5.0 * vz_mps  # damped hand
        z_m += h * vz_mps
        tick += 1
        if tick % int(args.rate) == 0:
            print(f"z = {z_m:+.4f} m, force z = {shown[2]:+.3f} N, client = {client}")
        time.sleep(max(0.0, start + tick * h - time.monotonic()))


if __name__ == "__main__":
    main()
