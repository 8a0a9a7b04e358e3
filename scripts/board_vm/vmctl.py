#!/usr/bin/env python3
"""The host side of one board-vm boot (scripts/board-vm runs it).

    vmctl.py --sockets DIR --out DIR --timeout S --expect a,b,... -- qemu-system-x86_64 ...

Listens on DIR/ctl, DIR/agent and DIR/qmp, starts QEMU (whose chardevs
connect to them), then serves the guest until it powers off or the timeout
passes. Standard library only.

The guest's requests, on the virtio-serial port board-vm.ctl: one line
each, answered with one line ("ok ..." or "error: ...").

    hello TEXT                      -> ok           (the payload has started)
    log TEXT                        -> ok           (shown on the host)
    check NAME PASS|FAIL DETAIL...  -> ok           (one line of the report)
    screendump NAME                 -> ok screen-NAME.png WxH colours=N
    gpio OFFSET pull-up|pull-down   -> ok value=V   (the host has the guest's
                                                     agent move the line)
    verify NAME KIND ARGS...        -> ok PASS|FAIL DETAIL  (the host checks
                                       what the guest left, records it as
                                       check NAME; verify.py has the kinds)
        screen-camera SCREEN                   the camera's picture and the status bar
        screen-matches SCREEN PNG MEAN P99     the screen shows guest/PNG
        png-matches PNG PNG MEAN P99           two of the guest's PNGs agree
        camera-report JSON MIN_FRAMES          a run on the camera: frames, stream, stage timings
    done                            -> ok           (the guest powers off next)

The agent, on the port board-vm.agent, says "hello" when it starts and
then answers the host's commands (pull, get, ping) with one line each: that
is the host's own way into the board (a hand on the button), which the
host can use without the guest asking, e.g. Controller.agent_command().

QMP (QEMU's machine protocol) gives the screendumps, as PPM, which are
written out as PNG here.

Exit status: 0 when every expected check passed, 1 when one failed or was
not reported, 2 when the run could not be done (QEMU failed, timeout).
"""

import argparse
import json
import os
import selectors
import socket
import struct
import subprocess
import sys
import time
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import verify  # noqa: E402  (next to this file)


def log(message):
    print(f"[board-vm {time.strftime('%H:%M:%S')}] {message}", file=sys.stderr, flush=True)


class LineChannel:
    """A connected socket read and written one text line at a time."""

    def __init__(self, sock, name):
        self.sock = sock
        self.name = name
        self.buffer = b""
        self.closed = False

    def fileno(self):
        return self.sock.fileno()

    def feed(self):
        """Reads what is there (the socket is readable); False at EOF."""
        data = self.sock.recv(65536)
        if not data:
            self.closed = True
            return False
        self.buffer += data
        return True

    def pop_line(self):
        if b"\n" not in self.buffer:
            return None
        line, self.buffer = self.buffer.split(b"\n", 1)
        return line.decode("utf-8", "replace").rstrip("\r")

    def readline(self, timeout):
        """The next line, waiting at most timeout seconds (None if none)."""
        deadline = time.monotonic() + timeout
        while True:
            line = self.pop_line()
            if line is not None or self.closed:
                return line
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self.sock.settimeout(left)
            try:
                if not self.feed():
                    return None
            except socket.timeout:
                return None
            finally:
                self.sock.settimeout(None)

    def send(self, line):
        self.sock.sendall(line.encode() + b"\n")


class Qmp:
    """Just enough of QMP: the greeting, capabilities, commands; events are kept."""

    def __init__(self, channel):
        self.channel = channel
        self.events = []
        greeting = channel.readline(60)
        if greeting is None or "QMP" not in greeting:
            raise RuntimeError(f"no QMP greeting (got {greeting!r})")
        self.execute("qmp_capabilities")

    def execute(self, command, timeout=60, **arguments):
        message = {"execute": command}
        if arguments:
            message["arguments"] = arguments
        self.channel.send(json.dumps(message))
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            line = self.channel.readline(deadline - time.monotonic())
            if line is None:
                break
            reply = json.loads(line)
            if "event" in reply:
                self.events.append(reply)
            elif "return" in reply:
                return reply["return"]
            elif "error" in reply:
                raise RuntimeError(f"QMP {command}: {reply['error'].get('desc', reply['error'])}")
        raise RuntimeError(f"QMP {command}: no answer")

    def pending_events(self):
        """Events that arrived while idle (call when the socket is readable)."""
        if not self.channel.feed():
            return []
        while (line := self.channel.pop_line()) is not None:
            try:
                reply = json.loads(line)
            except json.JSONDecodeError:
                continue
            if "event" in reply:
                self.events.append(reply)
        events, self.events = self.events, []
        return events


def read_ppm(path):
    """(width, height, RGB bytes) of a binary PPM (P6, maxval 255)."""
    with open(path, "rb") as f:
        data = f.read()
    fields, position = [], 0
    while len(fields) < 4:
        while data[position:position + 1].isspace():
            position += 1
        if data[position:position + 1] == b"#":
            position = data.index(b"\n", position) + 1
            continue
        end = position
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[position:end])
        position = end
    position += 1  # the single whitespace after maxval
    magic, width, height, maxval = fields[0], int(fields[1]), int(fields[2]), int(fields[3])
    if magic != b"P6" or maxval != 255:
        raise ValueError(f"{path}: not an 8-bit P6 PPM")
    pixels = data[position:position + width * height * 3]
    if len(pixels) != width * height * 3:
        raise ValueError(f"{path}: truncated")
    return width, height, pixels


def write_png(path, width, height, rgb):
    """An 8-bit RGB PNG, no filtering, with zlib: all the standard library has."""
    stride = width * 3
    raw = b"".join(b"\x00" + rgb[y * stride:(y + 1) * stride] for y in range(height))

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 6)))
        f.write(chunk(b"IEND", b""))


def colour_count(rgb, limit=64):
    """How many colours (up to limit): 1 means a blank screen."""
    colours = set()
    for i in range(0, len(rgb), 3 * 97):  # every 97th pixel is plenty
        colours.add(rgb[i:i + 3])
        if len(colours) >= limit:
            break
    return len(colours)


class Controller:
    def __init__(self, args):
        self.args = args
        self.out = os.path.abspath(args.out)
        self.expected = [name for name in args.expect.split(",") if name]
        self.checks = {}  # name -> (status, detail), in the order reported
        self.agent_ready = False
        self.guest_done = False
        self.start = time.monotonic()
        self.first_request = None
        self.qemu = None
        self.qmp = None
        self.ctl = None
        self.agent = None
        self.screens = {}  # screendump name -> (width, height, rgb)

    def elapsed(self):
        return time.monotonic() - self.start

    def record(self, name, status, detail=""):
        status = "PASS" if status == "PASS" else "FAIL"
        self.checks[name] = (status, detail)
        log(f"{status} {name}: {detail}")

    # -- the guest's requests -----------------------------------------------

    def handle_request(self, line):
        if self.first_request is None:
            self.first_request = self.elapsed()
            log(f"the guest's payload is up after {self.first_request:.0f} s")
        words = line.split(" ", 1)
        command, rest = words[0], (words[1] if len(words) > 1 else "")
        try:
            if command == "hello":
                return f"ok {self.elapsed():.0f}"
            if command == "log":
                log(f"guest: {rest}")
                return "ok"
            if command == "check":
                parts = rest.split(" ", 2)
                if len(parts) < 2:
                    return "error: check NAME PASS|FAIL DETAIL"
                self.record(parts[0], parts[1], parts[2] if len(parts) > 2 else "")
                return "ok"
            if command == "screendump":
                return self.screendump(rest.strip() or "screen")
            if command == "gpio":
                parts = rest.split()
                if len(parts) != 2:
                    return "error: gpio OFFSET pull-up|pull-down"
                return self.agent_command(f"pull {parts[0]} {parts[1]}")
            if command == "verify":
                return self.verify(rest.split())
            if command == "done":
                self.guest_done = True
                return "ok"
            return f"error: unknown request: {command}"
        except Exception as error:  # an answer, whatever went wrong, so the guest goes on
            return f"error: {error}"

    def screendump(self, name):
        name = "".join(c if c.isalnum() or c in "-_" else "_" for c in name)
        ppm = os.path.join(self.out, f"screen-{name}.ppm")
        png = os.path.join(self.out, f"screen-{name}.png")
        self.qmp.execute("screendump", filename=ppm)
        width, height, rgb = read_ppm(ppm)
        write_png(png, width, height, rgb)
        self.screens[name] = (width, height, rgb)
        os.unlink(ppm)
        colours = colour_count(rgb)
        log(f"screendump {png}: {width}x{height}, {colours}{'+' if colours >= 64 else ''} colours")
        if colours < 2:
            return f"error: screen-{name}.png {width}x{height} is blank (one colour)"
        return f"ok screen-{name}.png {width}x{height} colours={colours}"

    def guest_file(self, relative):
        path = os.path.normpath(os.path.join(self.out, "guest", relative))
        if not path.startswith(os.path.join(self.out, "guest") + os.sep):
            raise ValueError(f"{relative}: outside the guest's output folder")
        return path

    def verify(self, words):
        if len(words) < 2:
            return "error: verify NAME KIND ARGS..."
        name, kind, args = words[0], words[1], words[2:]
        try:
            if kind == "screen-camera" and len(args) == 1:
                passed, detail = verify.camera_picture_with_status_bar(self.screens[args[0]])
            elif kind == "screen-matches" and len(args) == 4:
                reference = verify.read_png(self.guest_file(args[1]))
                passed, detail = verify.images_match(self.screens[args[0]], reference, float(args[2]), int(args[3]))
                detail = f"screen-{args[0]}.png against guest/{args[1]}: {detail}"
            elif kind == "png-matches" and len(args) == 4:
                first, second = (verify.read_png(self.guest_file(a)) for a in args[:2])
                passed, detail = verify.images_match(first, second, float(args[2]), int(args[3]), letterboxed=False)
                detail = f"guest/{args[0]} against guest/{args[1]}: {detail}"
            elif kind == "camera-report" and len(args) == 2:
                report = verify.load_json(self.guest_file(args[0]))
                passed, detail = verify.camera_run_report(report, int(args[1]))
            elif kind == "camera-zero-copy" and len(args) in (2, 3):
                report = verify.load_json(self.guest_file(args[0]))
                passed, detail = verify.camera_zero_copy(report, int(args[1]), *args[2:])
            else:
                return f"error: verify {kind} with {len(args)} arguments: unknown"
        except KeyError as missing:
            passed, detail = False, f"no screendump {missing}"
        except (OSError, ValueError) as error:
            passed, detail = False, str(error)
        self.record(name, "PASS" if passed else "FAIL", detail)
        return f"ok {'PASS' if passed else 'FAIL'} {detail}"

    def agent_command(self, command, timeout=120):
        """Sends one command to the guest's agent; its one-line answer."""
        deadline = time.monotonic() + timeout
        while not self.agent_ready:  # the agent says hello when it has opened its port
            line = self.agent.readline(max(0.0, deadline - time.monotonic()))
            if line is None:
                return "error: the guest's agent did not start"
            if line.strip() == "hello":
                self.agent_ready = True
        self.agent.send(command)
        while True:
            line = self.agent.readline(max(0.0, deadline - time.monotonic()))
            if line is None:
                return f"error: no answer from the guest's agent to {command!r}"
            if line.strip() != "hello":  # a restarted agent says hello again
                log(f"agent: {command} -> {line}")
                return line

    # -- the run --------------------------------------------------------------

    def listen(self, name):
        path = os.path.join(self.args.sockets, name)
        if os.path.exists(path):
            os.unlink(path)
        server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        server.bind(path)
        server.listen(1)
        return server

    def accept_all(self, servers):
        """QEMU connects to the three sockets as it starts."""
        connected = {}
        deadline = time.monotonic() + 120
        selector = selectors.DefaultSelector()
        for name, server in servers.items():
            selector.register(server, selectors.EVENT_READ, name)
        while len(connected) < len(servers):
            if self.qemu.poll() is not None:
                raise RuntimeError(f"QEMU exited with status {self.qemu.returncode} as it started")
            if time.monotonic() > deadline:
                raise RuntimeError("QEMU did not connect to its sockets")
            for key, _ in selector.select(timeout=1):
                sock, _ = key.fileobj.accept()
                connected[key.data] = LineChannel(sock, key.data)
                selector.unregister(key.fileobj)
        for server in servers.values():
            server.close()
        return connected

    def run(self):
        os.makedirs(self.out, exist_ok=True)
        servers = {name: self.listen(name) for name in ("ctl", "agent", "qmp")}
        qemu_log = open(os.path.join(self.out, "qemu.log"), "w")
        log("starting QEMU: " + " ".join(self.args.qemu))
        self.qemu = subprocess.Popen(self.args.qemu, stdin=subprocess.DEVNULL, stdout=qemu_log,
                                     stderr=subprocess.STDOUT)
        status = "timeout"
        try:
            channels = self.accept_all(servers)
            self.ctl, self.agent = channels["ctl"], channels["agent"]
            self.qmp = Qmp(channels["qmp"])
            status = self.serve()
        except Exception as error:
            log(f"error: {error}")
            status = f"error: {error}"
        finally:
            self.stop_qemu()
            qemu_log.close()
        return self.report(status)

    def serve(self):
        selector = selectors.DefaultSelector()
        selector.register(self.ctl, selectors.EVENT_READ, "ctl")
        selector.register(self.agent, selectors.EVENT_READ, "agent")
        selector.register(self.qmp.channel, selectors.EVENT_READ, "qmp")
        deadline = self.start + self.args.timeout
        done_at = None
        while True:
            if self.qemu.poll() is not None:
                return "poweroff" if self.guest_done else f"QEMU exited (status {self.qemu.returncode})"
            now = time.monotonic()
            if now > deadline:
                return f"timeout after {self.args.timeout:.0f} s"
            if self.guest_done and done_at is None:
                done_at = now
            if done_at is not None and now - done_at > 180:
                return "the guest said done but did not power off"
            for key, _ in selector.select(timeout=1):
                if key.data == "ctl":
                    if not self.ctl.feed():
                        selector.unregister(self.ctl)
                        continue
                    while (line := self.ctl.pop_line()) is not None:
                        self.ctl.send(self.handle_request(line))
                elif key.data == "agent":
                    if not self.agent.feed():
                        selector.unregister(self.agent)
                        continue
                    while (line := self.agent.pop_line()) is not None:
                        if line.strip() == "hello":
                            self.agent_ready = True
                            log("the guest's agent is up")
                elif key.data == "qmp":
                    try:
                        events = self.qmp.pending_events()
                    except OSError:
                        events = []
                    if self.qmp.channel.closed:
                        selector.unregister(self.qmp.channel)
                    for event in events:
                        if event.get("event") in ("SHUTDOWN", "RESET", "GUEST_PANICKED"):
                            log(f"QEMU: {event['event']} {event.get('data', '')}")

    def stop_qemu(self):
        if self.qemu.poll() is not None:
            return
        try:
            self.qmp.execute("quit", timeout=10)
        except Exception:
            pass
        try:
            self.qemu.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.qemu.kill()
            self.qemu.wait()

    def report(self, status):
        total = self.elapsed()
        for name in self.expected:
            if name not in self.checks:
                self.checks[name] = ("FAIL", "not reported by the guest")
        finished = status == "poweroff"
        self.checks["guest-poweroff"] = ("PASS" if finished else "FAIL",
                                         "the payload finished and the guest powered off" if finished else status)
        lines = [f"{s} {name}: {detail}" for name, (s, detail) in self.checks.items()]
        failed = sum(1 for s, _ in self.checks.values() if s != "PASS")
        up = f"{self.first_request:.0f} s" if self.first_request is not None else "never"
        lines += ["", f"boot to the payload's first request: {up}; whole boot: {total:.0f} s; {status}",
                  f"{len(self.checks) - failed} passed, {failed} failed"]
        with open(os.path.join(self.out, "report.txt"), "w") as f:
            f.write("\n".join(lines) + "\n")
        print("\n".join(lines), flush=True)
        if not finished and status != "poweroff":
            console = os.path.join(self.out, "console.log")
            if os.path.exists(console):
                with open(console, "rb") as f:
                    text = f.read().decode("utf-8", "replace").replace("\r", "")
                    tail = [line for line in text.split("\n") if line.strip()][-25:]
                log("the end of console.log:\n    " + "\n    ".join(tail))
        if status.startswith("error") or status.startswith("timeout"):
            return 2
        return 1 if failed else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sockets", required=True, help="folder for the ctl, agent and qmp sockets")
    parser.add_argument("--out", required=True, help="folder for report.txt, screendumps, qemu.log")
    parser.add_argument("--timeout", type=float, default=1800, help="seconds for the whole boot")
    parser.add_argument("--expect", default="", help="comma-separated checks the guest must report")
    parser.add_argument("qemu", nargs=argparse.REMAINDER, help="-- then QEMU's command line")
    args = parser.parse_args()
    if args.qemu and args.qemu[0] == "--":
        args.qemu = args.qemu[1:]
    if not args.qemu:
        parser.error("no QEMU command line after --")
    sys.exit(Controller(args).run())


if __name__ == "__main__":
    main()
