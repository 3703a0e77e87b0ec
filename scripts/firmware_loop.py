#!/usr/bin/env python3
"""The firmware in the loop against the core, tick for tick: every shipped scene run twice by
host-sim, once with the core's board on the host and once with the firmware's link build
under QEMU (`host-sim run --firmware`), both with their history. The firmware is the core's
code for the M4F (IEEE f32, software libm) on the same ADC codes, so the two must agree bit
for bit: the same history.csv (per tick the DAC code, its power, the enable line, and the
plant they drove), the same report but for its run time, the same exit status, and the same telemetry stream
(`--record`: every field of each record, the firmware's read from its USART1).

Usage: scripts/firmware_loop.py HOST_SIM LINK_ELF OUT_DIR [SCENE...]
"""
import csv
import json
import subprocess
import sys
import time
from pathlib import Path


def run(host_sim, scene, out, firmware=None):
    """host-sim's JSON report, exit status and history rows for a scene; wall seconds."""
    cmd = [host_sim, "--json", "run", str(scene), "--history", "--record", "--out", str(out)]
    if firmware:
        cmd += ["--firmware", str(firmware)]
    started = time.monotonic()
    done = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - started
    if done.returncode not in (0, 1):
        sys.exit(f"{' '.join(cmd)}: exit {done.returncode}\n{done.stderr}")
    report = json.loads(done.stdout)
    name = report["scene"]
    with open(out / name / "history.csv", newline="") as f:
        rows = list(csv.reader(f))
    with open(out / name / "telemetry.csv", newline="") as f:
        records = [line for line in f if not line.startswith("#")]
    return report, done.returncode, rows, records, wall


def main():
    host_sim, elf, out = sys.argv[1], sys.argv[2], Path(sys.argv[3])
    scenes = [Path(s) for s in sys.argv[4:]] or sorted(Path("scenes").glob("*.toml"))
    total_ticks = 0
    failures = []
    print(f"{'scene':<26} {'ticks':>7} {'core s':>7} {'QEMU s':>7} {'ticks/s':>8}  agreement")
    for scene in scenes:
        core, core_status, core_rows, core_records, _ = run(host_sim, scene, out / "core")
        fw, fw_status, fw_rows, fw_records, wall = run(host_sim, scene, out / "firmware", elf)
        problems = []
        if core_status != fw_status:
            problems.append(f"exit status {core_status} (core) vs {fw_status} (firmware)")
        header = core_rows[0]
        for column in ("tick", "time_seconds", "dac_code", "dac_on", "enable", "phase"):
            if column not in header:
                problems.append(f"history.csv has no {column}")
        for i, (a, b) in enumerate(zip(core_rows[1:], fw_rows[1:])):
            if a != b:
                diff = [f"{h} {x} vs {y}" for h, x, y in zip(header, a, b) if x != y]
                problems.append(f"tick {a[0]} differs: {', '.join(diff)}")
                break
        if len(core_records) < 2 or core_records != fw_records:
            diff = next((f"{a.strip()} vs {b.strip()}" for a, b in zip(core_records, fw_records)
                         if a != b), f"{len(core_records)} vs {len(fw_records)} lines")
            problems.append(f"telemetry differs: {diff}")
        if len(core_rows) != len(fw_rows):
            problems.append(f"{len(core_rows) - 1} ticks (core) vs {len(fw_rows) - 1} (firmware)")
        for key in set(core) | set(fw):
            if key in ("run_seconds", "files"):
                continue
            if core.get(key) != fw.get(key):
                problems.append(f"report's {key}: {core.get(key)!r} vs {fw.get(key)!r}")
        ticks = len(core_rows) - 1
        total_ticks += ticks
        verdict = "identical" if not problems else "DIFFERENT: " + "; ".join(problems)
        print(f"{scene.stem:<26} {ticks:>7} {core['run_seconds']:>7.2f} {fw['run_seconds']:>7.2f} "
              f"{ticks / fw['run_seconds']:>8.0f}  {verdict}")
        if problems:
            failures.append(scene.stem)
    print(f"{total_ticks} ticks compared over {len(scenes)} scenes: DAC code, its power, the "
          f"enable line and the plant, tick for tick; the telemetry stream, record for record")
    if failures:
        sys.exit(f"the firmware and the core differ on: {', '.join(failures)}")


if __name__ == "__main__":
    main()
