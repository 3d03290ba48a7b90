#!/usr/bin/env python3
"""Measures the achieved rate of a shaped link with one TCP transfer.

  measure_rate.py recv PORT TIMEOUT_S       listens, receives until the sender closes, prints
                                             "BYTES SECONDS" (first byte to last byte)
  measure_rate.py send HOST PORT BYTES      connects (retrying for up to 5 s) and sends BYTES

Used by scripts/throttled_latency.sh, run inside the project's own network namespaces.
"""
import socket
import sys
import time


def recv(port: int, timeout_s: float) -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as server:
        server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        server.bind(("0.0.0.0", port))
        server.listen(1)
        server.settimeout(timeout_s)
        conn, _ = server.accept()
        with conn:
            conn.settimeout(timeout_s)
            total, first, last = 0, None, None
            while True:
                chunk = conn.recv(1 << 16)
                if not chunk:
                    break
                now = time.monotonic()
                first = now if first is None else first
                last = now
                total += len(chunk)
    if first is None or last <= first:
        print("measure_rate: nothing received", file=sys.stderr)
        return 1
    print(f"{total} {last - first:.6f}")
    return 0


def send(host: str, port: int, count: int) -> int:
    deadline = time.monotonic() + 5.0
    while True:
        try:
            conn = socket.create_connection((host, port), timeout=5.0)
            break
        except OSError:
            if time.monotonic() > deadline:
                print(f"measure_rate: cannot connect to {host}:{port}", file=sys.stderr)
                return 1
            time.sleep(0.05)
    with conn:
        block = bytes(1 << 16)
        left = count
        while left > 0:
            n = min(left, len(block))
            conn.sendall(block[:n])
            left -= n
    return 0


def main(argv: list) -> int:
    if len(argv) == 4 and argv[1] == "recv":
        return recv(int(argv[2]), float(argv[3]))
    if len(argv) == 5 and argv[1] == "send":
        return send(argv[2], int(argv[3]), int(argv[4]))
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
