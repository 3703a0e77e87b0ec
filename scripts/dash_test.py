#!/usr/bin/env python3
"""The live dashboard (`host-sim dash`) in Debian's Chromium, driven by selenium.

    scripts/dash_test.py serve HOST_SIM                 # against `host-sim serve` on scenes
    scripts/dash_test.py qemu HOST_SIM                  # against the firmware under QEMU
    scripts/dash_test.py bench HOST_SIM [--out FILE]    # 1 kHz of telemetry: kept, redraws, replies
    scripts/dash_test.py shot HOST_SIM PNG              # the README's screenshot

`serve`: the reference scene, then a fault scene. Asserts: no console errors on load; the
stream's sequence advances on the page, its gaps counted as the board's link counts them; a
target in the tunable range moves the bias (read back over the port by a second client and
on the page), and its reply within 100 ms of the click; the setting's help then says the new
target; one out of range shows the board's `err` verbatim; one tunable range in `safe`,
`info`, the page and the board (its ends taken and refused); Stop brings the plotted voltage
to 0 V and the output off; a fault scene shows the fault in words, in the fault log and its
descent at the slew rate, with STOP, the output and the fault in view at 360, 800 and 1,400 px;
`clear` then `start` ramps again; a recording made from the page has `console --record`'s
columns. Then (issue 58): a dash served beyond loopback refuses forged requests (no token, a
wrong one; 401) and the board never hears them, while its printed URL opens the page and drives
the board; a second dash says it does not control the board, and its STOP stops it; when the
first leaves, the second takes over and its plots move again; serve killed while driving: the
bar says the board is lost (never its last voltage), and the page recovers when serve is back.
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
import urllib.error
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


def dash(host_sim, board, stream_hz=250, listen="127.0.0.1:0"):
    """`host-sim dash` on the board: the process and the page's URL (its token in it)."""
    process = start([host_sim, "dash", *board, "--listen", listen,
                     "--stream-hz", str(stream_hz)])
    line = process.stdout.readline()
    if not line.startswith("dash: open "):
        process.kill()
        fail(f"dash printed no address: {line!r} {process.stderr.read()}")
    return process, line.split()[-1]


def base(url):
    """The page's address without its token: `http://host:port/`."""
    return url.split("?")[0]


def api(url, path, data=None, headers=None):
    """A request of dash's API as a tool makes it (the token in `Authorization`): its JSON."""
    token = url.split("token=")[1]
    request = urllib.request.Request(base(url) + path, data=data, headers={
        "Authorization": f"Token {token}", **(headers or {})})
    return json.loads(urllib.request.urlopen(request, timeout=10).read())


def http_code(url, path, data=None, headers=None):
    """The status code of a request (no token unless `headers` carry one)."""
    request = urllib.request.Request(url + path, data=data, headers=headers or {})
    try:
        return urllib.request.urlopen(request, timeout=10).status
    except urllib.error.HTTPError as e:
        return e.code


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

    def text(self, element_id):
        return self.d.find_element("id", element_id).text

    def in_view(self, element_id):
        """Whether the element is shown whole inside the viewport."""
        return self.js(f"""const r = document.getElementById("{element_id}").getBoundingClientRect();
            return r.width > 0 && r.height > 0 && r.left >= 0 && r.top >= 0 &&
                   r.right <= window.innerWidth && r.bottom <= window.innerHeight;""")


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
    token = url.split("token=")[1]
    for name in ("uPlot.iife.min.js", "uPlot.min.css"):
        served = urllib.request.urlopen(f"{base(url)}{name}?token={token}", timeout=10).read()
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
            state = api(url, "api/state")
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
            # The setting's help says the target now in force, not the one before.
            page.js("const s = document.getElementById('setting'); s.value = 'target_hz'; "
                    "s.dispatchEvent(new Event('change'))")
            wait_until(lambda: page.text("setting-help").endswith(f"now {target:g}"), 5,
                       f"the setting's help saying target_hz now {target:g}: "
                       f"{page.text('setting-help')!r}")
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
            one_range(host_sim, page)
            # A recording from the page: the columns `console --record` writes.
            page.click("record-start")
            time.sleep(1.5)
            page.click("record-stop")
            wait_until(lambda: page.d.find_element("id", "record-file").is_displayed(), 10,
                       "the recording's link")
            request = urllib.request.Request(base(url) + "api/recording.csv", headers={
                "Authorization": "Token " + url.split("token=")[1]})
            text = urllib.request.urlopen(request, timeout=10).read().decode()
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
            # The operating point's words under the curve, where no line's label covers them.
            now = page.text("curve-now")
            if not now.startswith("● now 0"):
                fail(f"the curve's operating point says {now!r} at 0 V")
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
            # The log in words: the entry's time and what happened, no protocol line.
            logged = wait_until(lambda: (lambda t: t if words.split(":")[0] in t and " s (tick "
                                         in t else None)(page.text("faults")), 10,
                                "the fault's entry in words in the page's fault log")
            if "ok faults=" in logged or "cause=" in logged:
                fail(f"the fault log shows protocol lines: {logged!r}")
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
            widths(page, words)
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


def one_range(host_sim, page):
    """One tunable range: `safe`'s (the reference device, margin 0.05, as the scene's image),
    the board's `info`, the page's words, and the board's own answer at each end (a target
    just inside taken, one just outside refused)."""
    out = subprocess.run([host_sim, "--json", "safe"], capture_output=True, text=True, check=True)
    lo, hi = json.loads(out.stdout)["tunable_range_hz"]
    info = fields_of(page.js("return dash.hello.info"))
    board = float(info["tunable_low_hz"]), float(info["tunable_high_hz"])
    for said, ours in zip(board, (lo, hi)):
        if abs(said - ours) > 1e-6 * ours:
            fail(f"`info` says the range {board}, `safe` {lo}..{hi}")
    shown = page.text("range")
    words = shown.split()
    page_lo, page_hi = float(words[2]), float(words[4])
    if not (lo <= page_lo < lo + 1e-4 and hi - 1e-4 < page_hi <= hi):
        fail(f"the page shows {shown!r}, `safe` {lo}..{hi}")
    # No AC (at the top end the bias is near 0 V, where an AC would swing below it).
    for request, taken in ((f"target {lo - 1e-3}", False), (f"target {hi + 1e-3}", False),
                           ("ac 0 40", True), (f"target {page_hi}", True),
                           (f"target {page_lo}", True)):
        wait_until(lambda: page.status().get("phase") in ("driving", "holding"), 30,
                   "the board at its bias")
        page.type("raw", request)
        reply, _ = page.reply_after(lambda: page.click("raw-send"))
        if reply.startswith("ok ") != taken:
            fail(f"`{request}` (the range {page_lo}..{page_hi}) got {reply!r}")
        time.sleep(0.6)  # the page's status polled past the reply
    print(f"dash_test (serve, range): safe {lo:.6f}..{hi:.6f} Hz, info {board[0]}..{board[1]}, "
          f"the page {page_lo}..{page_hi}: its ends taken by the board, 1 mHz beyond refused")


def widths(page, words):
    """STOP, the output and the latched fault in view at 360, 800 and 1,400 px, scrolled to the
    page's end too, and nothing wider than the window."""
    d = page.d
    try:
        for width in (360, 800, 1400):
            d.execute_cdp_cmd("Emulation.setDeviceMetricsOverride", {
                "width": width, "height": 800, "deviceScaleFactor": 1, "mobile": False})
            for scroll in (0, 100000):
                page.js(f"window.scrollTo(0, {scroll})")
                time.sleep(0.3)
                for element in ("stop", "output", "fault"):
                    if not page.in_view(element):
                        fail(f"#{element} out of view at {width} px (scrolled to {scroll})")
                if words not in page.text("fault"):
                    fail(f"the fault's words not in the bar at {width} px: {page.text('fault')!r}")
                wide = page.js("return document.documentElement.scrollWidth")
                if wide > width:
                    fail(f"the page is {wide} px wide in a window of {width} px")
            d.save_screenshot(str(ROOT / "target" / f"dash-{width}.png"))
    finally:
        d.execute_cdp_cmd("Emulation.clearDeviceMetricsOverride", {})
        page.js("window.scrollTo(0, 0)")
    print("dash_test (serve, widths): STOP, the output and the fault in view at 360, 800 and "
          "1400 px, at the top and the end of the page")


def forged(host_sim, driver):
    """Served beyond loopback: requests without the token, or with another, refused (401) and
    never heard by the board; the URL dash printed opens the page and switches it on."""
    board_process, board = serve_waiting(host_sim)
    try:
        dash_process, url = dash(host_sim, board, listen="0.0.0.0:0")
        try:
            port = base(url).rsplit(":", 1)[1].strip("/")
            if not url.startswith(f"http://127.0.0.1:{port}/?token="):
                fail(f"dash served on 0.0.0.0 printed {url} to open")
            # A forged request, as another machine would send it (its own Host and Origin;
            # sent here over loopback only).
            host = f"203.0.113.9:{port}"
            forged_headers = {"Host": host, "Origin": f"http://{host}", "X-Dash-Request": "1"}
            local = f"http://127.0.0.1:{port}/"
            for headers, path, data in (
                (forged_headers, "api/command", b"start"),
                ({**forged_headers, "Authorization": "Token 0123456789abcdef0123456789abcdef"},
                 "api/command", b"start"),
                ({**forged_headers, "Cookie": f"dash_token_{port}=guess"}, "api/command", b"target 44"),
                ({"Host": host}, "api/state", None),
                ({"Host": host}, "api/events", None),
                ({"Host": host}, "", None),
            ):
                code = http_code(local, path, data, headers)
                if code not in (401, 403):
                    fail(f"a forged request to /{path} got {code}, not 401/403")
            time.sleep(1.0)
            if api(url, "api/state")["link"]["requests"] != 0:
                fail("a forged request reached the board")
            said = port_status(host_sim, board)
            if said["output"] != "off" or float(said["volts"]) != 0.0:
                fail(f"the board moved after forged requests: {said}")
            # The printed URL: the page, and the board switched on from it.
            page = Page(driver, url)
            page.loads_live("dash.lastSeq")
            # Waiting for `start`: said as at rest, not as "holding … bias 0 V".
            rest = wait_until(lambda: (lambda t: t if t.startswith("at rest, 0 V") else None)(
                page.text("phase")), 5, f"the bar saying at rest: {page.text('phase')!r}")
            reply, _ = page.reply_after(lambda: page.click("start"))
            if not reply.startswith("ok "):
                fail(f"start from the printed URL's page got {reply!r}")
            wait_until(lambda: port_status(host_sim, board)["output"] == "on", 10,
                       "the board's output on after the page's start")
            page.click("stop")
            print("dash_test (serve, beyond loopback): 6 forged requests refused (401/403), the "
                  f"board never heard them; {rest!r}; the printed URL's page started the board")
        finally:
            stop(dash_process)
    finally:
        stop(board_process)


def serve_waiting(host_sim):
    """The reference scene's board waiting at power-up for `start` (the output off)."""
    command_port, stream_port = free_port(), free_port()
    process = start([host_sim, "serve", str(ROOT / "scenes" / "reference.toml"), "--tcp",
                     f"127.0.0.1:{command_port}", "--stream-tcp", f"127.0.0.1:{stream_port}",
                     "--power-up", "wait"])
    wait_port(command_port)
    return process, ["--tcp", f"127.0.0.1:{command_port}",
                     "--stream-tcp", f"127.0.0.1:{stream_port}"]


def two_dashes(host_sim, driver):
    """A second dash on the board: it says it does not control the board (and who does), only
    its STOP acts, and it stops the board; when the first leaves, it takes over and its plots
    move again (the stream asked anew)."""
    board_process, board = serve(host_sim, "reference.toml")
    try:
        first, _ = dash(host_sim, board)
        second, url = dash(host_sim, board)
        try:
            page = Page(driver, url)
            said = wait_until(lambda: (lambda t: t if "view only" in t else None)(
                page.text("control")), 10, "the second page saying it does not control")
            if not page.in_view("control"):
                fail("the control's words are not in the bar")
            for button in ("start", "target-send", "clear", "save"):
                if page.d.find_element("id", button).is_enabled():
                    fail(f"#{button} is enabled on a page that does not control the board")
            wait_until(lambda: port_status(host_sim, board)["output"] == "on", 30,
                       "the board driving")
            reply, _ = page.reply_after(lambda: page.click("stop"))
            if not reply.startswith("ok stop"):
                fail(f"STOP from the page that does not control got {reply!r}")
            wait_until(lambda: port_status(host_sim, board)["output"] == "off", 10,
                       "the board's output off after the second page's STOP")
            stop(first)
            wait_until(lambda: page.js("return dash.control.controls"), 10,
                       "the second page taking control as the first dash leaves")
            time.sleep(0.5)
            before = page.js("return dash.received")
            time.sleep(1.5)
            after = page.js("return dash.received")
            if not after > before + 100:
                fail(f"the plots stay frozen after taking control: {before} then {after} records")
            if "no records" in page.text("conn"):
                fail(f"the bar says {page.text('conn')!r}")
            print(f"dash_test (serve, two dashes): {said!r}; its STOP stopped the board; it took "
                  f"over as the first left, {after - before} records in 1.5 s")
        finally:
            stop(second)
            stop(first)
    finally:
        stop(board_process)


def lost(host_sim, driver):
    """serve killed while driving: the bar says the board is lost and its state unknown (never
    the last voltage), STOP says it cannot reach it; serve back on the same ports: the page
    live again, the output as the board says it."""
    command_port, stream_port = free_port(), free_port()
    command = [host_sim, "serve", str(ROOT / "scenes" / "reference.toml"), "--tcp",
               f"127.0.0.1:{command_port}", "--stream-tcp", f"127.0.0.1:{stream_port}"]
    board = ["--tcp", f"127.0.0.1:{command_port}", "--stream-tcp", f"127.0.0.1:{stream_port}"]
    board_process = start(command)
    wait_port(command_port)
    try:
        dash_process, url = dash(host_sim, board)
        try:
            page = Page(driver, url)
            wait_until(lambda: page.status().get("output") == "on", 30, "the board driving")
            os.killpg(board_process.pid, signal.SIGKILL)
            board_process.wait()
            badge = wait_until(lambda: (lambda t: t if "lost" in t else None)(page.text("output")),
                               10, "the bar saying the board is lost")
            if "state unknown" not in badge or " V" in badge:
                fail(f"the bar says {badge!r} with the board lost")
            if page.text("phase") or "reconnecting" not in page.text("conn"):
                fail(f"the bar still says {page.text('phase')!r} / {page.text('conn')!r}")
            if page.text("curve-now"):
                fail(f"the curve still shows the voltage: {page.text('curve-now')!r}")
            page.click("stop")
            wait_until(lambda: "the board is lost" in page.text("reply"), 5,
                       f"STOP with the board lost saying so: {page.text('reply')!r}")
            # The one error the browser logs: that STOP's 503 (the board out of reach).
            logged = [e["message"] for e in page.d.get_log("browser") if e["level"] == "SEVERE"]
            if any("503" not in m for m in logged):
                fail(f"console errors with the board lost: {logged}")
            board_process = start(command)
            wait_port(command_port)
            wait_until(lambda: page.text("output").startswith("output ON"), 30,
                       "the page live again once serve is back")
            received = page.js("return dash.received")
            wait_until(lambda: page.js("return dash.received") > received + 100, 10,
                       "the stream's records on the page again")
            print(f"dash_test (serve, lost): {badge!r} while serve was down, STOP said it cannot "
                  f"reach the board; live again: {page.text('output')!r}")
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
            state = api(url, "api/state")
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
            forged(host_sim, driver)
            two_dashes(host_sim, driver)
            lost(host_sim, driver)
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
