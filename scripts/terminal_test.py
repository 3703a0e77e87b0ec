#!/usr/bin/env python3
"""A person at a serial terminal: picocom (Debian's) in tmux, typing into the board's command
port on a pseudo-terminal, the screen read back with capture-pane.

    scripts/terminal_test.py serve HOST_SIM      # the virtual board: host-sim serve --pty
    scripts/terminal_test.py qemu HOST_SIM       # the firmware under QEMU: scripts/qemu.sh --pty

Types `status⏎`, then `stpo`, two backspaces, `op⏎` (a typo mended), then `help stop⏎`, and
asserts what the screen shows: each answered, the typing echoed after a prompt, the mended
line taken as `stop`; then Enter twice on an empty line (a fresh prompt each, no `err`)
and `get tick_hz⏎`; `stauts⏎` answered with the command meant (`status`). On `serve`, the
terminal closed and opened again hears the board's state at once (`# now phase=…`), and
Ctrl-C on serve says what the board was doing as it ends. Needs picocom and tmux
(scripts/test-all.sh installs them).
"""

import os
import pathlib
import shutil
import signal
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
SESSION = f"terminal-test-{os.getpid()}"


def fail(why, screen=""):
    print(f"terminal_test: {why}\n--- screen ---\n{screen}", file=sys.stderr)
    sys.exit(1)


def tmux(*args):
    return subprocess.run(["tmux", *args], capture_output=True, text=True, check=True).stdout


def screen():
    return tmux("capture-pane", "-t", SESSION, "-p")


def wait_for(text, seconds=30.0):
    """The screen once it shows `text`."""
    until = time.monotonic() + seconds
    while time.monotonic() < until:
        shown = screen()
        if text in shown:
            return shown
        time.sleep(0.2)
    fail(f"the screen never showed {text!r} in {seconds} s", screen())


def type_keys(*keys):
    tmux("send-keys", "-t", SESSION, *keys)


def board(mode, host_sim):
    """The board started on a pty: its process and the pty's path."""
    if mode == "serve":
        command = [host_sim, "serve", "--pty", "--speed", "1"]
        env = dict(os.environ)
    else:
        command = [str(ROOT / "scripts" / "qemu.sh"), "--pty"]
        env = dict(os.environ, HOST_SIM=host_sim)
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, env=env, start_new_session=True)
    path = process.stdout.readline().strip()
    if not path.startswith("/dev/"):
        process.kill()
        fail(f"{' '.join(command)} printed no pty: {path!r} {process.stderr.read()}")
    return process, path


def main():
    if len(sys.argv) != 3 or sys.argv[1] not in ("serve", "qemu"):
        print(__doc__, file=sys.stderr)
        return 2
    mode, host_sim = sys.argv[1], sys.argv[2]
    for tool in ("picocom", "tmux"):
        if shutil.which(tool) is None:
            fail(f"{tool} is not installed (apt-get install picocom tmux)")
    process, path = board(mode, host_sim)
    try:
        tmux("new-session", "-d", "-s", SESSION, "-x", "160", "-y", "40",
             f"picocom -q -b 115200 {path}")
        time.sleep(1.0)
        type_keys("status", "Enter")
        shown = wait_for("ok phase=")
        if "output=" not in shown:
            fail("status does not say whether the output is on", shown)
        # A typo mended with backspace: the port takes `stop`, and the terminal shows the
        # prompt and what was typed.
        type_keys("stpo", "BSpace", "BSpace", "op", "Enter")
        shown = wait_for("ok stop")
        if "> stop" not in shown:
            fail("the mended line is not shown after a prompt", shown)
        type_keys("help stop", "Enter")
        shown = wait_for("ok stop: AC off")
        if "> help stop" not in shown:
            fail("`help stop` is not echoed after a prompt", shown)
        # Enter on an empty line: a fresh prompt, no refusal; then a request still answered.
        type_keys("Enter", "Enter", "get tick_hz", "Enter")
        shown = wait_for("ok tick_hz")
        if "err 1" in shown:
            fail("a line was refused as not a request", shown)
        if ">\n>\n> get tick_hz" not in "\n".join(l.rstrip() for l in shown.splitlines()):
            fail("Enter on an empty line does not give a fresh prompt", shown)
        # A typo of a command: the one meant named, as `help <typo>` names it.
        type_keys("stauts", "Enter")
        shown = wait_for("did you mean `status`?")
        if mode == "serve":
            # The terminal closed and opened again: the board's state said at once.
            tmux("kill-session", "-t", SESSION)
            time.sleep(0.5)
            tmux("new-session", "-d", "-s", SESSION, "-x", "160", "-y", "40",
                 f"picocom -q -b 115200 {path}")
            wait_for("# now phase=")
            # Ctrl-C on serve: what the board was doing, said as it ends.
            os.killpg(process.pid, signal.SIGINT)
            _, said = process.communicate(timeout=30)
            if "interrupted at" not in said or "last status: phase=" not in said:
                fail(f"Ctrl-C on serve did not say the board's state: {said[-400:]!r}")
        print(f"terminal_test ({mode}): picocom on {path}: status answered, a typo mended, "
              "help stop answered, Enter on an empty line a fresh prompt, `stauts` answered "
              "with `status`" + (", the state said on reconnecting and at Ctrl-C"
                                 if mode == "serve" else ""))
        print(shown.rstrip())
        return 0
    finally:
        subprocess.run(["tmux", "kill-session", "-t", SESSION], capture_output=True)
        if process.poll() is None:
            try:
                os.killpg(process.pid, signal.SIGTERM)
            except ProcessLookupError:
                pass
            process.wait(timeout=30)


if __name__ == "__main__":
    sys.exit(main())
