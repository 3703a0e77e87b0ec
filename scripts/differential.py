#!/usr/bin/env python3
"""The virtual board against the firmware: one script of requests, two boards, every reply
compared field by field.

`host-sim serve` (the core's board on the host, against a scene's plant) and the firmware under
QEMU (netduinoplus2, the default QEMU build) boot the same image bytes: the scene below, written
into a temp dir, is served, and `host-sim image --scene` of it is flashed (`info`'s image_crc is
checked on both against the flashed file's). Both get the same script over their command port
(a Unix socket each), in every phase both can reach: ramping, holding, driving, stopped at rest,
at rest after a `reset` (the output off at 0 V, as at a power-up that waits), ramping after
`start`; on a second pair, the same board from an image that waits at power-up (`serve
--power-up wait`), at rest from the boot, then ramping after `target`, holding, driving,
down, ramping after `start`, down; on a
third, refused (settings the boot checks refuse), then at rest after `clear`, ramping,
driving the image's own AC, ramping down; on a fourth, faulted: the DAC's
bus broken 2 s after power-up (serve: the scene's `[faults] dac_bus_fails_after_seconds`;
the firmware: QEMU's `dac-bus-fails` switch, the same tick), latched at 0 V, `clear` refused
until the time a descent would take is over, then at rest, and faulted again at `start`'s
first frame, and again after `reset`. Bad input in every phase.

Each reply is read as fields: `ok` or `err <code>`, each `key=value` (a key said again
numbered: `t`, `t#2`, …), the free text (numbers in it apart, `text#1`, `text#2`, …); the
boot's and the reset's `# …` lines the same way. Every field must be equal but those in
EXCLUDED (the board's own figures, and what depends on when a request lands), each with its
reason. Prints a table of what was compared and every difference; exit status 1 on any
difference, or if a section of the script left the phase it was written for (then the boards
were not compared where meant).

The broken bus stays broken through `reset` on both (the firmware keeps the switch's break in
RAM a reset keeps, as a broken wire would stay broken). The other runtime
faults need an input (a sensor, the current or amplifier monitor, the trim, tracking), and
the default QEMU build reads none; they are the end-to-end test's (`sensor-fails`) and the
firmware-in-the-loop's.

Usage: scripts/differential.py [--keep] [ELF [HOST_SIM]]
  ELF       the firmware's QEMU build (default firmware/target/thumbv7em-none-eabihf/release/
            firmware: `cd firmware && cargo build --release --bin firmware`)
  HOST_SIM  host-sim (default $HOST_SIM, else target/debug/host-sim: `cargo build -p host-sim`)
The temp dir (scenes, images, sockets, logs, each board's transcript) is removed when the
boards agree (unless --keep), kept otherwise.
"""

import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import zlib

KEEP = "--keep" in sys.argv[1:]
sys.argv = [a for a in sys.argv if a != "--keep"]
ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
RUNNER = os.path.join(ROOT, "firmware", "qemu-run.sh")
ELF = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                      os.path.join(ROOT, "firmware/target/thumbv7em-none-eabihf/release/firmware"))
HOST_SIM = os.path.abspath(sys.argv[2] if len(sys.argv) > 2 else
                           os.environ.get("HOST_SIM") or os.path.join(ROOT, "target/debug/host-sim"))

# The board both run: the reference device, the default amplifier (2.5 V DAC reference, gain
# 4000, no rail below full scale), no front end and no sensors (the QEMU build reads none), the
# settings' defaults but a slower ramp (5 kV/s: 1.5 s to the 7,450 V bias, room for a batch of
# requests while ramping). A scene's image drives at power-up.
SCENE = """
name = "differential"
description = "the reference device at 44 Hz, no front end: serve against the firmware"
duration_seconds = 10.0

[amplifier]
dac_reference_volts = 2.5
gain = 4000.0

[controller]
target_hz = 44.0
slew_volts_per_second = 5000.0
"""
# The third pair: the image's settings have AC (100 V at 40 Hz) but at 600 Hz, above half the
# tick rate: the boot refuses them (a sound image: `set` and `clear` stay open). `image --scene`
# writes no image the firmware would refuse: the flashed one is the scene's at 40 Hz with
# ac_hz's value set to 600 and its CRC made again, and `info`'s image_crc says it is the
# bytes serve boots.
REFUSED_AC_HZ = 600.0
REFUSED_SCENE = SCENE.replace('"differential"', '"differential-refused"').replace(
    "slew_volts_per_second = 5000.0", "slew_volts_per_second = 5000.0\nac_volts = 100.0\nac_hz = {ac_hz}")
# The fourth pair: the scene's board with its DAC bus broken 2 s after power-up (serve: the
# scene's `[faults]`; the firmware: QEMU's `dac-bus-fails` switch, 2 s of ticks), after the
# ramp to the bias (1.5 s): a runtime fault latched at 0 V, its entry's `volts` the bias
# (checked: the fault came while holding).
BUS_FAILS_SECONDS = 2.0
FAULTED_SCENE = SCENE + f"""
[faults]
dac_bus_fails_after_seconds = {BUS_FAILS_SECONDS}
"""
# The fault each pair's faulted sections are for.
FAULT_WORDS = {"faulted": "DAC bus error"}
# One DAC step of the scene's amplifier (2.5 V reference, gain 4000, 16 bits), V.
DAC_STEP_VOLTS = 2.5 * 4000.0 / 65536
AC_HZ_ID = 6  # ac_hz's id (docs/settings.md)
SETTINGS_AT = 156  # the image's settings, by id, 8 bytes each from here (src/image.rs, layout 4)

# Asked in every section: what reads, bad input, the stream on and off.
COMMON = """status
info
get
get margin
get margn
help
help target
help ac_hz
help margn
faults
faults 1
frobnicate
target
target 4.4.4
target 44 kHz
stream 100
stream off
stream 0
stream 5000"""
# What needs the output at rest at 0 V, or changes nothing here: asked where it is refused.
WRONG_STATE = """save
reset
faults clear
clear"""
# Checked as a new plan and refused: out of range, above the cap, at the resonance of a device
# told no damping, a typo'd key, a fraction for a count, a rate fixed at power-up.
REFUSED_PLANS = """target 47
ac 1e6 40
ac 100 44
set margin 1.5
set margin 0.5
set margn 0.1
set stuck_samples 1.5
set tick_hz 500
trim"""

# `== kind: what` starts a section (kind: the phase it is written for, checked by the status
# at its start and end: ramping, holding, driving, rest, refused, faulted);
# `wait key=value[|value] … [S]` asks `status` until each holds (its last reply compared);
# `@COMMON`, `@WRONG_STATE`, `@REFUSED_PLANS` expand. After a new boot (`clear`, `reset`) the script waits for
# `phase=holding` before its next `status`: asked before the boot's first tick, both boards say
# `phase=ramping` (output off, 0 V), and whether a request lands before that tick is timing.
SCRIPT = """
== ramping: power-up (the scene's image drives at once)
status
== holding: at the bias
wait phase=holding
@COMMON
@WRONG_STATE
@REFUSED_PLANS
start
wait phase=holding
target 44
wait phase=holding
set slew_volts_per_second 5000
wait phase=holding
status
ac 100 40
== driving: after `ac 100 40`
wait phase=driving
@COMMON
@WRONG_STATE
@REFUSED_PLANS
start
wait phase=driving
ac 100 40
wait phase=driving
status
stop
== ramping: down after `stop`
@COMMON
@WRONG_STATE
status
== rest: stopped at 0 V
wait phase=holding volts=0
@COMMON
trim
stop
clear
wait phase=holding
set slew_volts_per_second 5000
save
faults clear
reset
== rest: after `reset` (the output off at 0 V, as at a power-up that waits)
wait phase=holding
@COMMON
@REFUSED_PLANS
get slew_volts_per_second
start
== ramping: just after `start`
@COMMON
@WRONG_STATE
target 44
ac 100 40
start
set slew_volts_per_second 5000
trim
status
stop
== ramping: down after `stop` while ramping up
status
== rest: stopped at 0 V from the ramp
wait phase=holding volts=0
status
"""

# The second pair: the same scene's image that waits at power-up (`image --scene --power-up
# wait`, `serve --power-up wait`), as `host-sim image`'s default board.
WAITS_SCRIPT = """
== rest: power-up with an image that waits (the output off at 0 V until `start`)
wait phase=holding
@COMMON
@REFUSED_PLANS
stop
wait phase=holding
trim
set slew_volts_per_second 5000
save
faults clear
clear
wait phase=holding
status
target 44
== ramping: after `target 44` (it switches the output on, as its help says)
@COMMON
status
== holding: at the bias
wait phase=holding
status
ac 100 40
== driving: after `ac 100 40`
wait phase=driving
status
stop
== rest: stopped at 0 V
wait phase=holding volts=0
status
start
== ramping: after `start`
status
stop
== rest: stopped at 0 V from the ramp
wait phase=holding volts=0
status
"""

REFUSED_SCRIPT = """
== refused: the image's settings refused at boot
@COMMON
@WRONG_STATE
trim
start
target 44
ac 100 40
stop
set margn 0.1
set ac_hz 1000
set ac_hz 40
status
clear
== rest: after `clear` (the output off at 0 V until `start`)
wait phase=holding
@COMMON
@REFUSED_PLANS
get ac_hz
start
== ramping: just after `start`, to the image's AC
@COMMON
@WRONG_STATE
start
status
== driving: the image's settings' AC
wait phase=driving
@COMMON
@WRONG_STATE
@REFUSED_PLANS
status
stop
== ramping: down after `stop`
@COMMON
start
status
== rest: stopped at 0 V
wait phase=holding volts=0
status
"""

FAULTED_SCRIPT = """
== faulted: the DAC's bus broken while holding (0 V at once, latched)
wait phase=faulted
clear
@COMMON
@REFUSED_PLANS
start
stop
target 44
ac 100 40
trim
set slew_volts_per_second 5000
save
faults clear
status
== faulted: the descent's time over (the output off)
wait output=off
@COMMON
save
faults 2
clear
== rest: after `clear`, the bus still broken
wait phase=holding
@COMMON
start
== faulted: again at `start`, the bus still broken
wait phase=faulted 1
status
faults
faults 2
stop
status
reset
== rest: after `reset`, the bus still broken (a wire stays broken through the chip's reset)
wait phase=holding
status
faults
start
== faulted: at `start` after the reset
wait phase=faulted 1
status
faults
faults 3
"""

# What is not compared: the board's own figures, and what depends on when a request lands.
# (field, the sections' kinds it holds for (None: all), the requests (None: all), why)
# `firmware=` is compared: both name the core's crate and version. No input is fitted, so no
# reading (`current_amps`, `amplifier_volts`, `stretch`) is in a reply to leave out.
MOVING = ("ramping", "driving")
# The faulted pair's last sections: their faults (the dead bus at `start`'s first DAC frame)
# logged at the tick the request landed.
AFTER_START = ("faulted: again at `start`, the bus still broken",
               "rest: after `reset`, the bus still broken (a wire stays broken through the chip's "
               "reset)",
               "faulted: at `start` after the reset")
EXCLUDED = [
    ("tick_cycles_max", None, None,
     "the worst tick in CPU cycles: silicon only (absent under QEMU and on serve)"),
    ("stack_bytes", None, None,
     "the firmware's stack high-water mark; serve runs on the host's stack (says 0)"),
    ("clock_us", None, None,
     "each board's own clock: QEMU's TIM2 from its start, serve's simulated time"),
    ("clock_tick", None, None,
     "the tick the clock was read at: the boards start and answer at other moments"),
    ("ticks", None, None,
     "ticks since boot when the request lands: the boards start and answer at other moments"),
    ("volts", MOVING, None,
     "the output where it is when the request lands, while it ramps or drives the AC"),
    ("text#1", MOVING, ("stop",),
     "`stop: ramp from <V> V`: the same moving output, where the ramp down starts"),
    ("text", MOVING, ("stop",),
     "`stop`'s words: a ramp down from where the output is, or none from 0 V (a ramp not yet "
     "begun when the request lands)"),
    ("text#2", MOVING, ("stop",), "the same: a ramp's end, 0 V, said only with a ramp"),
    ("t", AFTER_START, ("faults",),
     "the tick of a fault at `start`'s first write, when the request lands"),
    ("t#2", AFTER_START[2:], ("faults",), "the same, the one before it"),
    ("tick", AFTER_START, ("faults 2", "faults 3"), "the same faults' ticks"),
    ("seconds", AFTER_START, ("faults 2", "faults 3"), "the same faults' times"),
]


class Board:
    """One board's command port as a line stream; the replies of a script, with the time each
    section took."""

    def __init__(self, name, path, proc):
        self.name, self.proc = name, proc
        self.s = socket.socket(socket.AF_UNIX)
        for _ in range(400):
            try:
                self.s.connect(path)
                break
            except OSError:
                if proc.poll() is not None:
                    raise OSError(f"exited before serving {path}")
                time.sleep(0.05)
        else:
            raise OSError(f"nothing listens at {path}")
        self.s.settimeout(30)
        self.f = self.s.makefile("rwb", buffering=0)
        # The start-up lines, up to the one that says the boot's verdict.
        self.banner = [self.line()]
        while not re.match(r"# (ready|refused)", self.banner[-1]):
            self.banner.append(self.line())

    def line(self):
        raw = self.f.readline()
        if not raw:
            raise EOFError(f"{self.name} closed the command port")
        return raw.decode(errors="replace").rstrip("\r\n")

    def ask(self, request):
        """The lines a request gets: `# …` lines before its reply, the reply, and after a
        `reset` the new boot's lines up to its verdict."""
        self.f.write(request.encode() + b"\n")
        lines = [self.line()]
        while lines[-1].startswith("# "):
            lines.append(self.line())
        if request == "reset" and lines[-1].startswith("ok"):
            lines.append(self.line())
            while not re.match(r"# (ready|refused)", lines[-1]):
                lines.append(self.line())
        return lines

    def wait(self, conditions, seconds):
        """`status` until each `key=value[|value]` holds; the last reply (None: never)."""
        wanted = [(key, values.split("|")) for key, _, values in
                  (c.partition("=") for c in conditions)]
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            reply = self.ask("status")[-1]
            fields = fields_of(reply)
            if all(fields.get(key) in values for key, values in wanted):
                return reply
            time.sleep(0.05)
        return None

    def run(self, sections):
        """Each section's exchanges: (request, lines); a wait's, its last status."""
        self.out, self.seconds = [], []
        for _, requests in sections:
            began, done = time.monotonic(), []
            for request in requests:
                if request.startswith("wait "):
                    words = request.split()[1:]
                    seconds = [float(w) for w in words if "=" not in w]
                    reply = self.wait([w for w in words if "=" in w],
                                      seconds[0] if seconds else 30.0)
                    done.append((request, [reply if reply else f"(never: {request})"]))
                else:
                    done.append((request, self.ask(request)))
            self.out.append(done)
            self.seconds.append(time.monotonic() - began)


def fields_of(line):
    """A line's `key=value` pairs only (`fault=` and `words=` take the rest of the line)."""
    return dict(f for f in parse(line) if not f[0].startswith(("text", "reply")))


NUMBER = re.compile(r"(?<![\w.#])[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?(?![\w])")


def parse(line):
    """A line the board said, as fields: `reply` (`ok`, `err <code>` or `#`), each `key=value`
    (`fault=` and `words=` take the rest of the line: their sentence), and the free text with
    its numbers apart (`text` with each number `#`, then `text#1`, `text#2`, …). A key said
    again is numbered: `t`, `t#2`, …."""
    if line.startswith("err "):
        code, _, rest = line[4:].partition(" ")
        head = f"err {code}"
    elif line.startswith("ok"):
        head, rest = "ok", line[3:]
    elif line.startswith("# "):
        head, rest = "#", line[2:]
    else:
        head, rest = "(not a reply)", line
    out, words, seen = [("reply", head)], [], {}
    while rest:
        m = re.match(r"([a-z_][a-z0-9_.]*)=", rest)
        if m and m.group(1) in ("fault", "words"):
            out.append((m.group(1), rest[m.end():]))
            break
        token, _, rest = rest.partition(" ")
        if m:
            # A key said again (each entry's `t=` in `faults`' list): `t`, `t#2`, ….
            key = m.group(1)
            seen[key] = seen.get(key, 0) + 1
            out.append((key if seen[key] == 1 else f"{key}#{seen[key]}", token[m.end():]))
        elif token:
            words.append(token)
    if words:
        text = " ".join(words)
        numbers = NUMBER.findall(text)
        out.append(("text", NUMBER.sub("#", text)))
        out += [(f"text#{k}", n) for k, n in enumerate(numbers, 1)]
    return out


def excluded(field, kind, section, request):
    """The reason a field is not compared here (in a section of this kind, `kind: label`),
    or None."""
    for name, kinds, requests, why in EXCLUDED:
        if field == name and (kinds is None or kind in kinds or section in kinds) and \
                (requests is None or request in requests):
            return why
    return None


def expand(script):
    """The script's sections: (kind, label), requests."""
    macros = {"@COMMON": COMMON, "@WRONG_STATE": WRONG_STATE, "@REFUSED_PLANS": REFUSED_PLANS}
    sections = []
    for raw in script.strip().splitlines():
        line = raw.strip()
        if line.startswith("== "):
            kind, _, label = line[3:].partition(": ")
            sections.append(((kind, label), []))
        elif line in macros:
            sections[-1][1].extend(macros[line].splitlines())
        elif line:
            sections[-1][1].append(line)
    return sections


def host_sim(*args):
    done = subprocess.run([HOST_SIM, *args], capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"host-sim {' '.join(args)}: {done.stderr.strip()}")
    return done.stdout


def stop_group(proc):
    """SIGTERM the process group this script started (serve; the QEMU runner with QEMU and its
    log decoder) and wait for its leader."""
    try:
        os.killpg(proc.pid, signal.SIGTERM)
    except ProcessLookupError:
        pass
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()


def pair(work, name, scene_text, image_bytes, sections, qemu_args=None, power_up="drive"):
    """Serve the scene and run QEMU with the image, the script to both at once; each board's
    start-up lines and exchanges."""
    scene = os.path.join(work, f"{name}.toml")
    image = os.path.join(work, f"{name}.img")
    with open(scene, "w") as f:
        f.write(scene_text)
    with open(image, "wb") as f:
        f.write(image_bytes)
    sock = {k: os.path.join(work, f"{name}-{k}.sock") for k in ("serve", "serve-stream", "fw",
                                                                  "fw-stream")}
    serve = subprocess.Popen([HOST_SIM, "serve", scene, "--unix", sock["serve"], "--stream-unix",
                              sock["serve-stream"], "--power-up", power_up],
                             stdout=subprocess.DEVNULL,
                             stderr=open(os.path.join(work, f"{name}-serve.log"), "w"),
                             start_new_session=True)
    env = dict(os.environ, QEMU_IMAGE=image, QEMU_TIMEOUT="150",
               QEMU_SERIAL1=f"unix:{sock['fw']},server=on,wait=on",
               QEMU_SERIAL0=f"unix:{sock['fw-stream']},server=on,wait=off")
    env.pop("QEMU_EXTRA", None)
    env.pop("QEMU_ARGS", None)
    if qemu_args:
        env["QEMU_ARGS"] = qemu_args
    env.pop("QEMU_ICOUNT", None)
    qemu = subprocess.Popen([RUNNER, ELF], env=env,
                            stdout=open(os.path.join(work, f"{name}-firmware.log"), "w"),
                            stderr=subprocess.STDOUT, start_new_session=True)
    # Both connected at once: each boot's ramp starts as its board comes up (QEMU's at the
    # connection, after its boot checks; serve's after its own), the start-up lines read,
    # then the script.
    boards, errors = {}, []

    def run(who, path, proc):
        try:
            boards[who] = Board(who, path, proc)
            boards[who].run(sections)
        except (EOFError, OSError) as e:
            errors.append(f"{who}: {e}")
    try:
        threads = [threading.Thread(target=run, args=a) for a in
                   (("serve", sock["serve"], serve), ("firmware", sock["fw"], qemu))]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        stop_group(qemu)
        stop_group(serve)
    boards = [boards[who] for who in ("serve", "firmware") if who in boards]
    for board in boards:
        with open(os.path.join(work, f"{name}-{board.name}.txt"), "w") as f:
            f.write("\n".join(board.banner) + "\n")
            for (section, _), done in zip(sections, getattr(board, "out", [])):
                f.write(f"== {section[0]}: {section[1]}\n")
                for request, lines in done:
                    f.write(f"> {request}\n" + "".join(f"< {line}\n" for line in lines))
    if errors:
        sys.exit(f"{name}: {'; '.join(errors)} (logs in {work})")
    return boards


def compare(sections, serve, firmware, pair_name):
    """Rows of the table (one per request and section) and the differences, field by field."""
    rows, diffs, counts, phase_problems = [], [], {"compared": 0, "excluded": 0}, []
    exchanges = [[("(start-up lines)", serve.banner)], *serve.out]
    theirs = [[("(start-up lines)", firmware.banner)], *firmware.out]
    kinds = [("start-up", "")] + [s[0] for s in sections]
    for col, ((kind, label), ours, fws) in enumerate(zip(kinds, exchanges, theirs)):
        statuses = {"serve": [], "firmware": []}
        for (request, a), (_, b) in zip(ours, fws):
            for who, lines in (("serve", a), ("firmware", b)):
                if request == "status" or request.startswith("wait "):
                    statuses[who].append(fields_of(lines[-1]))
            different = []
            if len(a) != len(b):
                different.append(("lines", f"{len(a)} lines", f"{len(b)} lines"))
            for k, (la, lb) in enumerate(zip(a, b)):
                fa, fb = dict(parse(la)), dict(parse(lb))
                prefix = f"line {k + 1}: " if max(len(a), len(b)) > 1 else ""
                for field in list(dict.fromkeys([*fa, *fb])):
                    if excluded(field, kind, f"{kind}: {label}", request):
                        counts["excluded"] += 1
                        continue
                    counts["compared"] += 1
                    if fa.get(field) != fb.get(field):
                        different.append((prefix + field, fa.get(field, "(absent)"),
                                          fb.get(field, "(absent)")))
            rows.append((col, request, not different))
            for field, x, y in different:
                diffs.append((pair_name, f"{kind}: {label}".rstrip(": "), request, field, x, y,
                              a, b))
        # The section was asked in the phase it was written for (first and last status; a
        # faulted one for the pair's fault, at 0 V).
        want = {"rest": ("holding", "0", "off"), "refused": ("refused", "0", "off")}
        for who, seen in statuses.items():
            if kind != "start-up" and not seen:
                phase_problems.append(f"{pair_name}, {kind}: {label}: no status asked: its "
                                      f"phase unchecked")
            for s in (seen[:1] + seen[-1:]) if seen else []:
                phase = s.get("phase")
                if kind in want:
                    ok = (phase, s.get("volts"), s.get("output")) == want[kind]
                elif kind == "faulted":
                    ok = (phase, s.get("volts"), s.get("fault")) == \
                        ("faulted", "0", FAULT_WORDS.get(pair_name))
                else:
                    ok = kind in ("start-up",) or phase == kind
                if not ok:
                    phase_problems.append(f"{pair_name}, {kind}: {label}: {who}'s status says "
                                          f"phase={phase} volts={s.get('volts')} "
                                          f"output={s.get('output')} fault={s.get('fault')}")
    return rows, diffs, counts, phase_problems


def fault_while_holding(*boards):
    """The faulted pair's first fault came while holding the bias: its entry's `volts` (sent
    before it) within a DAC step of the boot's `bias_volts`. Problems, if not."""
    problems = []
    for board in boards:
        bias = float(fields_of(board.banner[-1]).get("bias_volts", "nan"))
        said = [fields_of(lines[-1]) for section in board.out for request, lines in section
                if request == "faults 1"]
        volts = [float(f.get("volts", "nan")) for f in said]
        if not volts or any(not abs(v - bias) <= DAC_STEP_VOLTS for v in volts):
            problems.append(f"faulted: {board.name}'s first fault sent {volts} V before it, not "
                            f"the bias {bias} V: the bus broke before the ramp was done")
    return problems


def table(pairs):
    """Requests down, sections across: `=` every compared field equal, `X` a difference."""
    for name, sections, rows in pairs:
        columns = [("start-up", "")] + [s[0] for s in sections]
        print(f"\n{name}: sections")
        for i, (kind, label) in enumerate(columns):
            print(f"  {i:>2}  {kind:<9} {label}")
        cells, order = {}, []
        for col, request, same in rows:
            if request not in order:
                order.append(request)
            if cells.get((request, col)) != "X":
                cells[(request, col)] = "=" if same else "X"
        width = max(len(r) for r in order)
        print(f"  {'request':<{width}}  " + " ".join(f"{i:>2}" for i in range(len(columns))))
        for request in order:
            print(f"  {request:<{width}}  " + " ".join(
                f"{cells.get((request, i), '.'):>2}" for i in range(len(columns))))


def main():
    for path, how in ((ELF, "cd firmware && cargo build --release --bin firmware"),
                      (HOST_SIM, "cargo build -p host-sim")):
        if not os.path.exists(path):
            sys.exit(f"differential: no {path} ({how})")
    began = time.monotonic()
    work = tempfile.mkdtemp(prefix="differential-")

    # The images: the scene's own bytes (what serve boots); the refused one made from its
    # twin at 40 Hz (`image --scene` writes no refused image), ac_hz set, the CRC again.
    with open(os.path.join(work, "good.toml"), "w") as f:
        f.write(SCENE)
    host_sim("image", "--scene", os.path.join(work, "good.toml"), "--out",
             os.path.join(work, "good.img"))
    good = open(os.path.join(work, "good.img"), "rb").read()
    host_sim("image", "--scene", os.path.join(work, "good.toml"), "--power-up", "wait",
             "--out", os.path.join(work, "waits.img"))
    waits = open(os.path.join(work, "waits.img"), "rb").read()
    with open(os.path.join(work, "twin.toml"), "w") as f:
        f.write(REFUSED_SCENE.format(ac_hz=40.0))
    host_sim("image", "--scene", os.path.join(work, "twin.toml"), "--out",
             os.path.join(work, "twin.img"))
    body = bytearray(open(os.path.join(work, "twin.img"), "rb").read()[:-4])
    at = SETTINGS_AT + 8 * AC_HZ_ID
    assert struct.unpack_from("<H", body, at)[0] == AC_HZ_ID, "the image's layout moved"
    struct.pack_into("<f", body, at + 4, REFUSED_AC_HZ)
    refused = bytes(body) + struct.pack("<I", zlib.crc32(body))

    pairs, all_diffs, problems = [], [], []
    totals = {"compared": 0, "excluded": 0, "exchanges": 0}
    for name, scene, image, script, qemu_args, power_up in (
            ("drives", SCENE, good, SCRIPT, None, "drive"),
            ("waits", SCENE, waits, WAITS_SCRIPT, None, "wait"),
            ("refused", REFUSED_SCENE.format(ac_hz=REFUSED_AC_HZ), refused, REFUSED_SCRIPT,
             None, "drive"),
            ("faulted", FAULTED_SCENE, good, FAULTED_SCRIPT, "dac-bus-fails", "drive")):
        sections = expand(script)
        serve, firmware = pair(work, name, scene, image, sections, qemu_args, power_up)
        rows, diffs, counts, phase_problems = compare(sections, serve, firmware, name)
        pairs.append((name, sections, rows))
        all_diffs += diffs
        problems += phase_problems
        totals["compared"] += counts["compared"]
        totals["excluded"] += counts["excluded"]
        totals["exchanges"] += len(rows)
        # The same bytes booted: image_crc on both the flashed file's.
        crc = f"0x{zlib.crc32(image[:-4]):08x}"
        for board in (serve, firmware):
            said = [fields_of(lines[-1]).get("image_crc")
                    for section in board.out for request, lines in section if request == "info"]
            if not said or any(c != crc for c in said):
                problems.append(f"{name}: {board.name}'s info says image_crc {set(said)}, the "
                                f"flashed image's CRC is {crc}")
        if name == "faulted":
            problems += fault_while_holding(serve, firmware)
        times = ", ".join(f"{(s[0][0])} {a:.1f}/{b:.1f} s"
                          for s, a, b in zip(sections, serve.seconds, firmware.seconds))
        print(f"{name}: serve/firmware seconds a section: {times}")

    table(pairs)
    print("\nnot compared (EXCLUDED):")
    for field, kinds, requests, why in EXCLUDED:
        where = "everywhere" if kinds is None else "while " + " or ".join(kinds)
        if kinds and ": " in kinds[0]:
            where = "in " + ", ".join(f"`{k.split(' (')[0]}`" for k in kinds)
        if requests:
            where += f", in {', '.join(requests)}'s reply"
        print(f"  {field:<16} {where}: {why}")
    print(f"\n{totals['exchanges']} exchanges, {totals['compared']} fields compared, "
          f"{totals['excluded']} excluded, {len(all_diffs)} differences, "
          f"{time.monotonic() - began:.1f} s")
    for name, where, request, field, x, y, a, b in all_diffs:
        print(f"\nDIFFERENCE ({name}) {where}: `{request}`: {field}\n"
              f"  serve:    {x}\n  firmware: {y}")
        for who, lines in (("serve", a), ("firmware", b)):
            for line in lines:
                print(f"  {who + ':':<9} | {line}")
    for p in problems:
        print(f"PROBLEM: {p}")
    if all_diffs or problems:
        print(f"\nthe boards differ: transcripts, logs, scenes and images kept in {work}")
        sys.exit(1)
    if KEEP:
        print(f"transcripts, logs, scenes and images kept in {work}")
    else:
        shutil.rmtree(work, ignore_errors=True)
    print("serve and the firmware agree on every compared field")


if __name__ == "__main__":
    main()
