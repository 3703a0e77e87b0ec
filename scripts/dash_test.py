#!/usr/bin/env python3
"""The live dashboard (`host-sim dash`) in Debian's Chromium, driven by selenium.

    scripts/dash_test.py serve HOST_SIM                 # against `host-sim serve` on scenes
    scripts/dash_test.py qemu HOST_SIM                  # against the firmware under QEMU
    scripts/dash_test.py bench HOST_SIM [--out FILE]    # 1 kHz of telemetry: kept, redraws, replies
    scripts/dash_test.py shot HOST_SIM PNG              # the README's screenshot

`serve`: the reference scene, then a fault scene. Asserts: no console errors on load; the
stream's sequence advances on the page, its gaps counted as the board's link counts them; a
target in the tunable range moves the bias (read back over the port by a second client and
on the page), and its reply within 100 ms of the click; one out of range shows the board's
`err` verbatim; Stop brings the plotted voltage to 0 V and the output off; a fault scene
shows the fault in words, in the fault log and its descent at the slew rate; `clear` then
`start` ramps again; a recording made from the page has `console --record`'s columns.
`qemu`: the page against the firmware (scripts/qemu.sh --no-console): loads, shows live
records and the board's status. Needs chromium, chromium-driver and selenium 4.51.0
(scripts/test-all.sh installs them).
"""

import csv
import hashlib
import io
import json
import os
import pathlib
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request

ROOT = pathlib.Path(__file__).resolve().parents[1]
UPLOT = ROOT / "host-sim" / "assets" / "uplot"


def fail(why):
    print(f"dash_test: {why}", file=sys.stderr)
    sys.exit(1)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start(command, env=None):
    """A process in a session of its own (stopped with its children)."""
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env, start_new_session=True)


def stop(process):
    try:
        os.killpg(process.pid, signal.SIGINT)
        process.wait(timeout=15)
    except ProcessLookupError:
        pass
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()


def wait_until(check, seconds, what):
    until = time.monotonic() + seconds
    while time.monotonic() < until:
        value = check()
        if value:
            return value
        time.sleep(0.05)
    fail(f"{what}: not within {seconds} s")


def wait_port(port, seconds=30):
    def up():
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.2):
                return True
        except OSError:
            return False
    wait_until(up, seconds, f"nothing listens on port {port}")


def serve(host_sim, scene, speed="1"):
    """`host-sim serve` on a scene: the process, its command port and stream port."""
    command_port, stream_port = free_port(), free_port()
    process = start([host_sim, "serve", str(ROOT / "scenes" / scene), "--tcp",
                     f"127.0.0.1:{command_port}", "--stream-tcp", f"127.0.0.1:{stream_port}",
                     "--speed", speed])
    wait_port(command_port)
    return process, ["--tcp", f"127.0.0.1:{command_port}",
                     "--stream-tcp", f"127.0.0.1:{stream_port}"]


def dash(host_sim, board, stream_hz=250):
    """`host-sim dash` on the board: the process and the page's address."""
    process = start([host_sim, "dash", *board, "--listen", "127.0.0.1:0",
                     "--stream-hz", str(stream_hz)])
    line = process.stdout.readline()
    if not line.startswith("dash: open "):
        process.kill()
        fail(f"dash printed no address: {line!r} {process.stderr.read()}")
    return process, line.split()[-1]


def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    options = Options()
    options.binary_location = "/usr/bin/chromium"
    # As this machine's probe starts it: no background networking (the network is closed).
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--window-size=1600,1250",
                 f"--user-data-dir={tempfile.mkdtemp(prefix='dash-chromium-')}"):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)


class Page:
    def __init__(self, driver, url):
        self.d = driver
        self.url = url
        # A page of an earlier dash (stopped) goes first, and what the browser logged for it
        # (its events' reconnections) with it.
        driver.get("about:blank")
        driver.get_log("browser")
        driver.get(url)
        wait_until(lambda: self.js("return window.dash && dash.hello !== null"), 20,
                   "the page's hello")

    def js(self, body):
        return self.d.execute_script(body)

    def loads_live(self, counter, seconds=1.0):
        """No console error on load, and `counter` (a page expression) advancing."""
        errors = self.errors()
        if errors:
            fail(f"console errors on load: {errors}")
        first = wait_until(lambda: self.js(f"return {counter}"), 30, f"{counter} on the page")
        time.sleep(seconds)
        later = self.js(f"return {counter}")
        if not later > first:
            fail(f"{counter} did not advance on the page: {first} then {later}")
        return later

    def errors(self):
        """The browser's console errors and the page's own."""
        logged = [e["message"] for e in self.d.get_log("browser") if e["level"] == "SEVERE"]
        return logged + self.js("return dash.errors")

    def click(self, element_id):
        self.d.find_element("id", element_id).click()

    def type(self, element_id, text):
        field = self.d.find_element("id", element_id)
        field.clear()
        field.send_keys(text)

    def reply_after(self, action):
        """Do `action`, then the reply the page shows (verbatim) and the ms it took."""
        self.js("dash.lastReply = ''")
        action()
        reply = wait_until(lambda: self.js("return dash.lastReply"), 10, "a reply on the page")
        shown = self.d.find_element("id", "reply").text
        if reply not in shown:
            fail(f"the page holds {reply!r} but shows {shown!r}")
        return reply, self.js("return dash.lastReplyMs")

    def status(self):
        return self.js("return dash.status && dash.status.fields") or {}


def port_status(host_sim, board):
    """`status` asked over the board's command port by a second client (read-only)."""
    with tempfile.NamedTemporaryFile("w", suffix=".txt") as script:
        script.write("status\n")
        script.flush()
        out = subprocess.run([host_sim, "--json", "console", *board[:2], "--script",
                              script.name], capture_output=True, text=True, timeout=30)
    report = json.loads(out.stdout)
    return report["exchanges"][0]["fields"]


def fields_of(reply):
    return dict(w.split("=", 1) for w in reply.split()[1:] if "=" in w)


def check_assets(url):
    """The vendored uPlot served as its README's hashes say."""
    listed = (UPLOT / "README.md").read_text()
    for name in ("uPlot.iife.min.js", "uPlot.min.css"):
        served = urllib.request.urlopen(url + name, timeout=10).read()
        digest = hashlib.sha256(served).hexdigest()
        if digest not in listed:
            fail(f"{name} served with sha256 {digest}, not the one host-sim/assets/uplot/README.md lists")


def console_columns(host_sim, board):
    """The columns `console --record` writes, from a one-second recording of the board."""
    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp) / "console.csv"
        subprocess.run([host_sim, "console", *board, "--record", str(path),
                        "--duration-seconds", "1"], capture_output=True, text=True, check=True,
                       timeout=60)
        return [l for l in path.read_text().splitlines() if not l.startswith("#")][0]


def reference(host_sim, driver, screenshot=None):
    board_process, board = serve(host_sim, "reference.toml")
    try:
        columns = console_columns(host_sim, board)
        dash_process, url = dash(host_sim, board)
        try:
            check_assets(url)
            page = Page(driver, url)
            # The stream's sequence advances; gaps counted as the board's link counts them.
            page.loads_live("dash.lastSeq")
            state = json.loads(urllib.request.urlopen(url + "api/state", timeout=10).read())
            gaps = page.js("return dash.gaps")
            if gaps != state["link"]["lost"]:
                fail(f"the page counts {gaps} gaps where the link lost {state['link']['lost']}")
            # The reference scene ramps to its target as it boots: in range, a new target.
            wait_until(lambda: page.status().get("phase") in ("driving", "holding"), 30,
                       "the board at its bias")
            lo, hi = page.js("return dash.hello.curve.tunable_range_hz")
            before = float(page.status()["bias_volts"])
            target = round(lo + 0.8 * (hi - lo), 3)
            page.type("target-hz", str(target))
            reply, ms = page.reply_after(lambda: page.click("target-send"))
            if not reply.startswith("ok "):
                fail(f"`target {target}` in the range {lo}..{hi} got {reply!r}")
            if ms > 100:
                fail(f"the reply to `target {target}` took {ms:.1f} ms from the click (> 100 ms)")
            bias = float(fields_of(reply)["bias_volts"])
            if abs(bias - before) < 1.0:
                fail(f"target {target} Hz did not move the bias ({before} V to {bias} V)")
            over_port = float(port_status(host_sim, board)["bias_volts"])
            if abs(over_port - bias) > 1e-3 * bias:
                fail(f"the port reads bias {over_port} V, the reply said {bias} V")
            wait_until(lambda: abs(float(page.status().get("bias_volts", 0)) - bias) < 1e-3 * bias,
                       5, f"the page's status showing bias {bias} V")
            # Out of range, once the ramp is done: the board's refusal, verbatim.
            wait_until(lambda: page.status().get("phase") in ("driving", "holding"), 30,
                       "the board at its new bias")
            page.type("target-hz", str(round(hi + 10.0, 3)))
            reply, _ = page.reply_after(lambda: page.click("target-send"))
            if not reply.startswith("err "):
                fail(f"a target above the range got {reply!r}")
            if screenshot:
                time.sleep(4.0)
                driver.save_screenshot(str(screenshot))
            # A recording from the page: the columns `console --record` writes.
            page.click("record-start")
            time.sleep(1.5)
            page.click("record-stop")
            wait_until(lambda: page.d.find_element("id", "record-file").is_displayed(), 10,
                       "the recording's link")
            text = urllib.request.urlopen(url + "api/recording.csv", timeout=10).read().decode()
            rows = [l for l in text.splitlines() if not l.startswith("#")]
            if rows[0] != columns:
                fail(f"the page's recording has columns {rows[0]!r}, console's {columns!r}")
            if len(rows) < 100:
                fail(f"1.5 s at 250 Hz recorded only {len(rows) - 1} rows")
            for header in ("# info: ok ", "# get: ok ", "# status: ok ", "# stream 250: ok "):
                if header not in text:
                    fail(f"the recording's header lacks {header!r}")
            # Stop: the plotted voltage down to 0 V, the output off.
            page.click("stop")
            wait_until(lambda: page.js("const v = dash.cols.volts; return v.length && v[v.length-1] === 0"),
                       10, "the plotted voltage at 0 V after Stop")
            wait_until(lambda: page.status().get("output") == "off", 5, "status: the output off")
            badge = page.d.find_element("id", "output").text
            if "off" not in badge:
                fail(f"the page's badge says {badge!r} after Stop")
            errors = page.errors()
            if errors:
                fail(f"console errors: {errors}")
            received = page.js("return dash.received")
            print(f"dash_test (serve, reference): {received} records on the page, {gaps} gaps; "
                  f"target {target} Hz moved the bias {before:.1f} V to {bias:.1f} V (port: "
                  f"{over_port:.1f} V), reply in {ms:.1f} ms; out of range: {reply!r}; "
                  f"{len(rows) - 1} rows recorded with console's columns; Stop to 0 V")
        finally:
            stop(dash_process)
    finally:
        stop(board_process)


def fault(host_sim, driver):
    # The ADC stalls at 14 s of board time, the second time within 10 s: a fault; it then
    # samples again, so `clear` and `start` can ramp again. At 3x real time.
    board_process, board = serve(host_sim, "fault-adc-stall.toml", speed="3")
    try:
        dash_process, url = dash(host_sim, board)
        try:
            page = Page(driver, url)
            words = wait_until(lambda: page.status().get("fault") not in (None, "none")
                               and page.js("return dash.status.line.split(' fault=')[1]"), 20,
                               "a fault in the board's status")
            shown = wait_until(lambda: (lambda t: t if words in t else None)(
                page.d.find_element("id", "fault").text), 5, "the fault in words on the page")
            wait_until(lambda: "cause=" in page.d.find_element("id", "faults").text, 10,
                       "the fault's entry in the page's fault log")
            wait_until(lambda: page.js("const v = dash.cols.volts; return v.length && v[v.length-1] === 0"),
                       10, "the plotted voltage at 0 V after the fault")
            # The descent as plotted: from the fault's record to 0 V, never up, and no
            # faster than the slew rate allows.
            cols = page.js("return {t: dash.cols.t, v: dash.cols.volts, f: dash.cols.fault}")
            first = next(i for i, f in enumerate(cols["f"]) if f)
            down = cols["v"][first:]
            end = next(i for i, v in enumerate(down) if v == 0.0)
            slew = float(next(s["value"] for s in page.js("return dash.hello.settings")
                              if s["key"] == "slew_volts_per_second"))
            steps = list(zip(cols["t"][first:first + end + 1], down[:end + 1]))
            for (t0, v0), (t1, v1) in zip(steps, steps[1:]):
                if v1 > v0:
                    fail(f"the plotted voltage rose during the descent: {v0} V to {v1} V")
                if v0 - v1 > slew * (t1 - t0) * 1.01 + 1e-3:
                    fail(f"the plotted descent is faster than the slew: {v0} V to {v1} V in {t1 - t0} s")
            if end < 10:
                fail(f"the descent from {down[0]} V is {end} records: not shown")
            # clear, then start: ramping again.
            reply, _ = page.reply_after(lambda: page.click("clear"))
            if not reply.startswith("ok "):
                fail(f"`clear` got {reply!r}")
            count = page.js("return dash.cols.t.length")
            reply, _ = page.reply_after(lambda: page.click("start"))
            if not reply.startswith("ok "):
                fail(f"`start` after `clear` got {reply!r}")
            wait_until(lambda: page.js(f"return dash.cols.volts.slice({count}).some(v => v > 100)"),
                       10, "the voltage rising again after clear and start")
            page.click("stop")
            errors = page.errors()
            if errors:
                fail(f"console errors: {errors}")
            print(f"dash_test (serve, fault): {shown!r}; the descent {down[0]:.0f} V to 0 V in "
                  f"{end} records, never up, within the slew; clear and start ramp again")
        finally:
            stop(dash_process)
    finally:
        stop(board_process)


def qemu(host_sim, driver):
    socket_path = ROOT / "target" / "qemu" / "dash.sock"
    stream_path = ROOT / "target" / "qemu" / "dash-stream.sock"
    board_process = start([str(ROOT / "scripts" / "qemu.sh"), "--no-console", "--socket",
                           str(socket_path)], env=dict(os.environ, HOST_SIM=host_sim))
    try:
        wait_until(lambda: socket_path.exists() and stream_path.exists(), 300,
                   f"QEMU's sockets at {socket_path}")
        dash_process, url = dash(host_sim, ["--unix", str(socket_path), "--stream-unix",
                                            str(stream_path)], stream_hz=100)
        try:
            page = Page(driver, url)
            later = page.loads_live("dash.received", seconds=2.0)
            fields = wait_until(lambda: page.status().get("output") and page.status(), 10,
                                "the firmware's status on the page")
            crc = page.js("return dash.hello.image_crc")
            print(f"dash_test (qemu): the page against the firmware: {later} records, status "
                  f"phase={fields['phase']} output={fields['output']}, image {crc}")
        finally:
            stop(dash_process)
    finally:
        stop(board_process)


def bench(host_sim, driver, out):
    """1 kHz of telemetry for 10 s on a 10 s window: every record kept, redraws a second,
    the time from a click to its reply on the page."""
    board_process, board = serve(host_sim, "resonant-ac.toml")
    try:
        dash_process, url = dash(host_sim, board, stream_hz=1000)
        try:
            page = Page(driver, url)
            wait_until(lambda: page.js("return dash.received") > 0, 10, "records")
            first, received0, redraws0 = page.js(
                "return [dash.lastSeq, dash.received, dash.redraws]")
            t0 = time.monotonic()
            fps = []
            while time.monotonic() - t0 < 10.0:
                time.sleep(1.0)
                fps.append(page.js("return dash.fps"))
            elapsed = time.monotonic() - t0
            last, received, redraws = page.js(
                "return [dash.lastSeq, dash.received, dash.redraws]")
            received -= received0
            redraws -= redraws0
            window = page.js("const t = dash.cols.t; return t.length ? t[t.length-1] - t[0] : 0")
            kept = page.js("return dash.cols.t.length")
            state = json.loads(urllib.request.urlopen(url + "api/state", timeout=10).read())
            replies = []
            for _ in range(10):
                page.type("raw", "status")
                _, ms = page.reply_after(lambda: page.click("raw-send"))
                replies.append(ms)
            draw_ms = page.js("return dash.drawMs")
            result = {
                "stream_hz": 1000,
                "seconds": round(elapsed, 2),
                "records_on_page": received,
                "sequence_span": (last - first) % 2**32,
                "gaps_on_page": page.js("return dash.gaps"),
                "lost_board_to_dash": state["link"]["lost"],
                "dropped_dash_to_page": state["link"]["dropped_to_pages"],
                "records_held": kept,
                "held_seconds": round(window, 3),
                "redraws_per_second": round(redraws / elapsed, 1),
                "fps_samples_min": min(fps),
                "last_draw_ms": round(draw_ms, 2),
                "reply_ms_median": round(sorted(replies)[len(replies) // 2], 1),
                "reply_ms_max": round(max(replies), 1),
            }
            print(json.dumps(result, indent=1))
            if out:
                pathlib.Path(out).write_text(json.dumps(result, indent=1) + "\n")
            if result["records_on_page"] != result["sequence_span"] - result["gaps_on_page"]:
                fail("records lost between the board and the page")
            if result["gaps_on_page"] or result["dropped_dash_to_page"]:
                fail("records dropped on the way to the page")
            if result["redraws_per_second"] < 20 or result["reply_ms_max"] > 100:
                fail("below 20 redraws a second, or a reply later than 100 ms")
        finally:
            stop(dash_process)
    finally:
        stop(board_process)


def main():
    args = sys.argv[1:]
    if len(args) < 2 or args[0] not in ("serve", "qemu", "bench", "shot"):
        print(__doc__, file=sys.stderr)
        return 2
    mode, host_sim = args[0], args[1]
    driver = browser()
    try:
        if mode == "serve":
            reference(host_sim, driver)
            fault(host_sim, driver)
        elif mode == "qemu":
            qemu(host_sim, driver)
        elif mode == "bench":
            bench(host_sim, driver, args[3] if len(args) > 3 and args[2] == "--out" else None)
        else:
            if len(args) != 3:
                print(__doc__, file=sys.stderr)
                return 2
            reference(host_sim, driver, screenshot=pathlib.Path(args[2]).resolve())
    finally:
        driver.quit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
