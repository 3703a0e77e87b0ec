#!/usr/bin/env python3
"""The trim on the charge against the current monitor's noise (BENCHMARKS.md, "The charge's
resolution"): the reference device without a displacement sensor, the plant's μ scaled, at
each window and noise level, one run per seed. Prints each run's outcome: its frequency's
relative error, or its fault (the resolution it said, when the ring was too weak to time).
Built with `MIN_RESOLUTION` lifted (src/estimate/ring.rs), every run says its first resolution.

Usage: scripts/charge_resolution.py HOST_SIM [SEEDS]
"""
import json
import os
import re
import subprocess
import sys
import tempfile

SCENE = """name = "charge-resolution"
duration_seconds = 8.0
seed = {seed}

[plant]
shear_modulus_scale = {scale}
quality_factor = 200.0
leakage_ohms = 1e12

[amplifier]
bandwidth_hz = 2000.0
slew_volts_per_second = 200000.0

[current_monitor]
noise_amps = {noise}
sample_hz = 10000.0
resolution_amps = 1e-7

[controller]
target_hz = 44.0
ac_volts = 100.0
ac_hz = 40.0
trim_tolerance = 1e-3
probe_volts = 20.0
probe_hz = 500.0
trim_window_seconds = {window}
"""

CASES = [(0.5, 5e-6), (0.5, 8e-6), (0.5, 1.2e-5), (1.0, 1.2e-5), (1.0, 2e-5), (0.25, 5e-6)]


def main():
    host_sim = sys.argv[1]
    seeds = int(sys.argv[2]) if len(sys.argv) > 2 else 6
    with tempfile.TemporaryDirectory() as work:
        path = os.path.join(work, "scene.toml")
        print("window_s noise_amps scale outcomes (relative error, or R=resolution, or fault)")
        for window, noise in CASES:
            for scale in (0.97, 1.03):
                outcomes = []
                for seed in range(1, seeds + 1):
                    with open(path, "w") as f:
                        f.write(SCENE.format(seed=seed, scale=scale, noise=noise, window=window))
                    done = subprocess.run([host_sim, "run", "--json", "--out", work, path],
                                          capture_output=True, text=True)
                    run = json.loads(done.stdout)
                    fault = run["fault"]
                    said = re.search(r"resolution of ([0-9.e+-]+)", fault or "")
                    if said:
                        outcomes.append(f"R={float(said.group(1)):.0f}")
                    elif fault:
                        outcomes.append("fault")
                    else:
                        outcomes.append(f"{run['relative_error']:+.1e}")
                print(window, noise, scale, " ".join(outcomes), flush=True)


if __name__ == "__main__":
    main()
