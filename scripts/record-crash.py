#!/usr/bin/env python3
"""What a crash leaves of a recording: runs `snaked --emulated --record`, kills it with
SIGKILL SECONDS into the run, and reads the file back the ways a user would.

    scripts/record-crash.py [--snaked target/debug/snaked] [--seconds 10] [--world W]

Prints the cycles the loop had run (`status` over the control socket just before the
kill), then what each reader gets from the killed file: the documented recipe
(`make_reader(f).iter_messages()`), the non-seeking reader in its default order and
with `log_time_order=False`, and, when the binary has it, `snaked --recover` followed
by the documented recipe. A share is the /joints messages read over the cycles run
(a period the loop skipped, as a debug build on a busy machine does, has no message).
Needs Python's mcap package (pip install mcap)."""
import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time

from mcap.reader import NonSeekingReader, make_reader


def call(sock_path, method):
    with socket.socket(socket.AF_UNIX) as s:
        s.connect(sock_path)
        s.sendall(json.dumps({"id": 1, "method": method, "params": {}}).encode() + b"\n")
        buf = b""
        while not buf.endswith(b"\n"):
            buf += s.recv(65536)
        return json.loads(buf)["result"]


def joints(iterate):
    """(count, last cycle) of /joints, or the exception the reader raised."""
    n, last = 0, None
    try:
        for _, channel, message in iterate():
            if channel.topic == "/joints":
                n += 1
                last = json.loads(message.data)["cycle"]
    except Exception as e:  # noqa: BLE001 - the point is to report what a reader does
        return n, last, f"{type(e).__name__}: {str(e)[:80]}"
    return n, last, None


def report(label, result, cycles):
    n, last, err = result
    share = 100.0 * n / cycles if cycles else 0.0
    lost = f", the last {cycles - 1 - last} cycles missing" if last is not None else ""
    tail = f"; raised {err}" if err else ""
    print(f"  {label:40} {n:>6} /joints ({share:5.1f} %){lost}{tail}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--snaked", default="target/debug/snaked")
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--world", help="a world scenario (default: the joint-space plant)")
    args = ap.parse_args()

    d = tempfile.mkdtemp()
    path, sock = os.path.join(d, "run.mcap"), os.path.join(d, "s.sock")
    cmd = [args.snaked, "--emulated", "--socket", sock, "--record", path]
    if args.world:
        cmd += ["--world", args.world]
    daemon = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while not os.path.exists(sock):
            if time.monotonic() > deadline or daemon.poll() is not None:
                sys.exit("snaked did not start")
            time.sleep(0.05)
        while True:
            status = call(sock, "status")
            if status["t_s"] >= args.seconds:
                break
            time.sleep(0.01)
        dropped = call(sock, "stats")["record_dropped"]
        daemon.send_signal(signal.SIGKILL)
        daemon.wait()
    finally:
        if daemon.poll() is None:
            daemon.kill()
    cycles = status["cycle"] + 1
    print(f"{args.snaked}: SIGKILL at t = {status['t_s']:.3f} s, cycle {status['cycle']} "
          f"({cycles} cycles, {dropped} dropped by the ring); "
          f"{os.path.getsize(path)} bytes on disk")

    def recipe(p):
        def it():
            with open(p, "rb") as f:
                yield from make_reader(f).iter_messages()
        return it

    def non_seeking(p, **kw):
        def it():
            with open(p, "rb") as f:
                yield from NonSeekingReader(f).iter_messages(**kw)
        return it

    report("make_reader(f).iter_messages()", joints(recipe(path)), cycles)
    report("NonSeekingReader, default order", joints(non_seeking(path)), cycles)
    report("NonSeekingReader, log_time_order=False",
           joints(non_seeking(path, log_time_order=False)), cycles)
    out = os.path.join(d, "run.recovered.mcap")
    rec = subprocess.run([args.snaked, "--recover", path, out], capture_output=True, text=True)
    if rec.returncode != 0:
        print(f"  snaked --recover: exit {rec.returncode}: {rec.stderr.strip()[:120]}")
        return
    print("  " + rec.stdout.strip().replace("\n", "\n  "))
    report("snaked --recover, then make_reader(...)", joints(recipe(out)), cycles)


if __name__ == "__main__":
    main()
