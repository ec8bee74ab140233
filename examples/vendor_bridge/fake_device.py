#!/usr/bin/env python3
"""A device server for the rigidtouch UDP device protocol, version 3, in plain Python.

It simulates a hand that taps downwards along -z and streams its state to the one renderer that
holds the session; the newest command's force, clamped to this device's limit, pushes back on the
simulated hand. Every datagram carries an HMAC-SHA-256 under the pre-shared key (the same key file
`rigidtouch device-sim` and `rigidtouch serve` use). Use it as a template for an SDK with Python
bindings: replace the simulated hand with the SDK's reads and writes. See docs/device-protocol.md.
Python's sleep is not a real-time clock: expect jitter. Standard library only.

    python3 fake_device.py --listen udp://127.0.0.1:47000 --rate 1000 [--key FILE] [--max-force 3.3]
                           [--duration S] [--json]

With --json it prints one JSON object when it ends (--duration, SIGINT or SIGTERM): the largest
force it displayed, the sessions it accepted, the datagrams it took and dropped, and the
handshake packets it refused as replays.
"""
import argparse, hashlib, hmac, json, math, os, signal, socket, stat, struct, time

MAGIC, VERSION = 0x48435452, 3
STATE, COMMAND, HELLO, HELLO_REPLY = 1, 2, 3, 4
HEADER = struct.Struct("<IHHIIQQQ")  # magic, version, type, payload bytes, reserved,
#                                      client nonce, server nonce, counter
STATE_PAYLOAD = struct.Struct("<Q14dI")   # sequence, time, p(3), q(4 wxyz), v(3), w(3), buttons
COMMAND_PAYLOAD = struct.Struct("<Q6dI")  # sequence, force(3), torque(3), flags
REPLY_PAYLOAD = struct.Struct("<3d")      # max force N, max stiffness N/m, max damping N s/m
MAC_BYTES = 32
SIZES = {HELLO: 0, COMMAND: COMMAND_PAYLOAD.size}  # what a device server accepts


def default_key_path():
    xdg = os.environ.get("XDG_CONFIG_HOME", "")
    if xdg.startswith("/"):
        return os.path.join(xdg, "rigidtouch", "device.key")
    return os.path.join(os.path.expanduser("~"), ".config", "rigidtouch", "device.key")


def load_key(path, create):
    """The key file's 32 bytes; refuses a file group or others may access, as ssh does."""
    if create and not os.path.exists(path):
        os.makedirs(os.path.dirname(path), mode=0o700, exist_ok=True)
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "w") as f:
            f.write(os.urandom(32).hex() + "\n")
    info = os.lstat(path)
    if not stat.S_ISREG(info.st_mode) or info.st_uid != os.geteuid():
        raise SystemExit(f"{path}: not a regular file owned by this user")
    if info.st_mode & 0o077:
        raise SystemExit(f"{path}: permissions {info.st_mode & 0o777:04o} are too open; "
                         f"run `chmod 600 {path}`")
    with open(path) as f:
        text = f.read().strip()
    if len(text) != 64:
        raise SystemExit(f"{path}: malformed, expected 64 hexadecimal digits")
    return bytes.fromhex(text)


def seal(key, kind, payload, client_nonce, server_nonce, counter):
    body = HEADER.pack(MAGIC, VERSION, kind, len(payload), 0, client_nonce, server_nonce,
                       counter) + payload
    return body + hmac.new(key, body, hashlib.sha256).digest()


def open_datagram(key, data):
    """(type, client nonce, server nonce, counter, payload) of an authentic datagram, else None.
    The checks follow the document's order: framing (version 1 is refused here), then the MAC."""
    if len(data) < HEADER.size + MAC_BYTES:
        return None
    magic, version, kind, size, _, client_nonce, server_nonce, counter = HEADER.unpack_from(data)
    if magic != MAGIC or version != VERSION or SIZES.get(kind) != size:
        return None
    if len(data) != HEADER.size + size + MAC_BYTES:
        return None
    mac = hmac.new(key, data[:-MAC_BYTES], hashlib.sha256).digest()
    if not hmac.compare_digest(mac, data[-MAC_BYTES:]):
        return None
    return kind, client_nonce, server_nonce, counter, data[HEADER.size:-MAC_BYTES]


def random_nonce():
    while True:
        nonce = struct.unpack("<Q", os.urandom(8))[0]
        if nonce:
            return nonce


def clamp(force, limit_N):
    norm = math.sqrt(sum((f / 1e150) ** 2 for f in force)) * 1e150  # no overflow near 1e300
    return force if limit_N <= 0 or norm <= limit_N else tuple(f * limit_N / norm for f in force)


def stop_on_signal(signum, frame):
    raise KeyboardInterrupt  # SIGTERM ends the loop as Ctrl-C does, and the summary is printed


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--listen", default="udp://127.0.0.1:47000", help="udp://HOST:PORT")
    parser.add_argument("--rate", type=float, default=1000.0, help="Hz")
    parser.add_argument("--watchdog", type=float, default=0.05, help="s")
    parser.add_argument("--session-timeout", type=float, default=0.5, help="s")
    parser.add_argument("--duration", type=float, default=0.0, help="s, 0 = until Ctrl-C")
    parser.add_argument("--key", default="", help="key file; default: the per-user key")
    parser.add_argument("--max-force", type=float, default=3.3, help="N, this device's limit")
    parser.add_argument("--json", action="store_true", help="print a JSON summary at the end")
    args = parser.parse_args()
    if not (math.isfinite(args.max_force) and args.max_force > 0):
        raise SystemExit(f"--max-force {args.max_force}: must be a positive number of newtons")
    signal.signal(signal.SIGTERM, stop_on_signal)
    key = load_key(args.key or default_key_path(), create=not args.key)
    limits = REPLY_PAYLOAD.pack(args.max_force, 0.0, 0.0)
    # the same address form as rigidtouch's own flags (udp://HOST:PORT); HOST:PORT also works
    address = args.listen[len("udp://"):] if args.listen.startswith("udp://") else args.listen
    host, port = address.rsplit(":", 1)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind((host, int(port)))
    sock.setblocking(False)

    h, mass_kg, z_m, vz_mps = 1.0 / args.rate, 0.1, 0.05, 0.0
    # the session: peer address, both nonces, counters, newest command
    peer, client_nonce, server_nonce, sent, received = None, 0, 0, 0, 0
    # the handshake: challenges in flight {(address, client nonce): (server nonce, sent at)},
    # and every client nonce challenged so far (a hello seen before is a replay: refused)
    challenges, seen_hellos = {}, set()
    last_heard, newest, force_N, fresh_at = -1.0, -1, (0.0, 0.0, 0.0), -1.0
    summary = {"max_displayed_force_N": 0.0, "sessions": 0, "commands": 0, "dropped": 0,
               "replayed_handshakes": 0}
    start = time.monotonic()
    tick = 0
    try:
        while args.duration <= 0 or time.monotonic() - start < args.duration:
            now = time.monotonic()
            if peer is not None and now - last_heard > args.session_timeout:
                peer = None  # the renderer went silent: its session ends
            if peer is not None:  # 1. read the device (here: simulate it) and send its state
                sent += 1
                state = (sent, now - start, 0.0, 0.0, z_m, 1.0, 0.0, 0.0, 0.0,
                         0.0, 0.0, vz_mps, 0.0, 0.0, 0.0, 0)
                sock.sendto(seal(key, STATE, STATE_PAYLOAD.pack(*state), client_nonce,
                                 server_nonce, sent), peer)
            for _ in range(64):  # 2. take hellos and commands, at most 64 per period
                try:
                    data, source = sock.recvfrom(512)
                except BlockingIOError:
                    break
                opened = open_datagram(key, data)
                if opened is None:
                    summary["dropped"] += 1
                    continue
                kind, cn, sn, counter, payload = opened
                if kind == HELLO:
                    if cn == 0 or (peer is not None and source != peer):
                        summary["dropped"] += 1  # one renderer at a time: no takeover
                        continue
                    if sn == 0:  # asks for a session: challenge it, open nothing
                        if (source, cn) in challenges:  # our challenge was lost: resend it
                            challenge = challenges[(source, cn)][0]
                        elif cn in seen_hellos:  # a hello seen before: a replay
                            summary["replayed_handshakes"] += 1
                            continue
                        else:
                            challenge = random_nonce()
                            seen_hellos.add(cn)
                            challenges[(source, cn)] = (challenge, now)
                        sock.sendto(seal(key, HELLO_REPLY, limits, cn, challenge, 0), source)
                        continue
                    # confirms a challenge: only the holder of the key can, once, and in time
                    pending = challenges.pop((source, cn), None)
                    if (pending is None or pending[0] != sn
                            or now - pending[1] > args.session_timeout):
                        summary["replayed_handshakes"] += 1
                        continue
                    peer, client_nonce, server_nonce = source, cn, sn  # a new session
                    sent, received, newest, fresh_at = 0, 0, -1, -1.0
                    last_heard = now
                    summary["sessions"] += 1
                    continue
                if (source != peer or (cn, sn) != (client_nonce, server_nonce)
                        or counter <= received):
                    summary["dropped"] += 1  # outside the session, or replayed
                    continue
                sequence, fx, fy, fz, tx, ty, tz, flags = COMMAND_PAYLOAD.unpack(payload)
                if not all(math.isfinite(v) for v in (fx, fy, fz, tx, ty, tz)):
                    summary["dropped"] += 1
                    continue
                received, last_heard = counter, now
                summary["commands"] += 1
                if sequence >= newest:
                    newest, force_N, fresh_at = sequence, clamp((fx, fy, fz), args.max_force), now
            # 3. display the force, or zero when the watchdog has tripped or there is no session
            fresh = peer is not None and fresh_at >= 0 and now - fresh_at <= args.watchdog
            shown = force_N if fresh else (0.0, 0.0, 0.0)
            shown_N = math.sqrt(sum(f * f for f in shown))
            summary["max_displayed_force_N"] = max(summary["max_displayed_force_N"], shown_N)
            hand_N = -0.5 if math.sin(2.0 * math.pi * 1.0 * (now - start)) > 0 else 0.3
            vz_mps += h * (hand_N + shown[2]) / mass_kg - h * 5.0 * vz_mps  # damped hand
            z_m += h * vz_mps
            tick += 1
            if tick % int(args.rate) == 0 and not args.json:
                print(f"z = {z_m:+.4f} m, force z = {shown[2]:+.3f} N, client = {peer}, "
                      f"dropped = {summary['dropped']}", flush=True)
            time.sleep(max(0.0, start + tick * h - time.monotonic()))
    except KeyboardInterrupt:
        pass
    if args.json:
        print(json.dumps(summary), flush=True)


if __name__ == "__main__":
    main()
