#!/usr/bin/env bash
# host-sim against its peers, side by side in one run.
# 1. Work-precision (issue 63; scripts/peers/work_precision.py): error against run time on two
#    scenes of the reference device, our DOP853, Radau and the core's fixed-step methods beside
#    SciPy's DOP853, Radau and LSODA, numbalsoda's DOP853 and CVODE's BDF, tolerances 1e-4 …
#    1e-12, the median of RUNS launches a point, whole process and in process; writes
#    docs/plots/work-precision-peers{.csv,.svg,-whole.svg}.
# 2. The goals' tables (issue 13):
#    - `host-sim simulate` (reference DOP853), whole process, against numbalsoda's DOP853
#      (Hairer's code in C++, a numba-compiled right-hand side) in-process with the JIT
#      excluded, on the reference scene: 7000 V + 200 V at 30 Hz, 10 s, output every 1/64 of
#      the zero-bias period, rtol = atol = 1e-12;
#    - `host-sim simulate --method reference-bdf`, whole process, against SUNDIALS CVODE's BDF
#      (scripts/peers/cvode_scene.c, compiled here), whole process, on a damped scene where
#      BDF is the right choice: the same drive with c = 10 N·s from the pre-stretch, 1 s, 1e-10.
#    - Radau IIA 5 (every build) and BDF against CVODE on the damped scene and a stiff one
#      (c = 10,000 N·s at 5912.84 V, issue 29's), all from the pre-stretch, 1 s, 1e-10.
# The peers restate the equations (scripts/peers/scene.py and the C file), sharing no code
# with the core; each comparison checks the final states agree before it times anything.
# Usage: scripts/bench-peers.sh [RUNS]    both, host-sim's peak build (RUNS: 10)
#        scripts/bench-peers.sh --check   (CI) 1 only, fewer points, one launch each, with
#                                         $HOST_SIM (default target/debug/host-sim): the
#                                         figures' words and each point's times (within 4×
#                                         after the machine's factor, the peers' median)
#                                         and errors against docs/plots/
#        scripts/bench-peers.sh --install the peers only (CI installs them beside its builds)
# Installs gfortran and libsundials-dev with apt where missing, and the peers at the versions
# named below into target/peers-venv.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-10}
case "$mode" in
    -h|--help) sed -n '2,28p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    --check|--install|[0-9]*) ;;
    *) echo "bench-peers.sh: unknown argument \`$mode\` (see --help)" >&2; exit 2 ;;
esac
SUDO=$([ "$(id -u)" = 0 ] && echo || echo sudo)
need=()
command -v gfortran >/dev/null || need+=(gfortran)
[ -f /usr/include/cvode/cvode.h ] || need+=(libsundials-dev)
if [ ${#need[@]} -gt 0 ]; then
    $SUDO apt-get update -qq
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${need[@]}"
fi
# The peers' versions, named (BENCHMARKS.md quotes them with the figures).
PEERS="numbalsoda==0.3.4 numba==0.68.1 scipy==1.17.1 numpy==2.4.6 matplotlib==3.11.2"
VENV=target/peers-venv
if [ ! -x "$VENV/bin/python" ] || [ "$(cat "$VENV/peers" 2>/dev/null)" != "$PEERS" ]; then
    # A Debian system Python has venv apart (python3-venv); pyenv's has it built in.
    if ! python3 -m venv --clear "$VENV" 2>/dev/null; then
        $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv
        python3 -m venv --clear "$VENV"
    fi
    # shellcheck disable=SC2086
    "$VENV/bin/pip" install --quiet --disable-pip-version-check $PEERS
    echo "$PEERS" >"$VENV/peers"
fi
# SUNDIALS as apt has it (Debian 12: 6.4.1), named with the figures.
sundials=$(sed -n 's/^#define SUNDIALS_VERSION "\(.*\)"/\1/p' /usr/include/sundials/sundials_config.h)
echo "$sundials" >"$VENV/sundials"
gcc -O2 -Wall -o target/cvode_scene scripts/peers/cvode_scene.c \
    -lsundials_cvode -lsundials_nvecserial -lm
[ "$mode" = --install ] && exit 0
if [ "$mode" = --check ]; then
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    "$VENV/bin/python" scripts/peers/work_precision.py --check --runs 1 \
        --host-sim "${HOST_SIM:-target/debug/host-sim}" --cvode target/cvode_scene --out "$tmp" \
        --versions "$PEERS sundials==$sundials"
    exit 0
fi
RUNS=$mode
cargo build --locked --profile peak -p host-sim --features bdf --quiet
"$VENV/bin/python" scripts/peers/work_precision.py --runs "$RUNS" \
    --host-sim target/peak/host-sim --cvode target/cvode_scene --out docs/plots \
    --versions "$PEERS sundials==$sundials"
"$VENV/bin/python" - "$RUNS" <<'PY'
import json, subprocess, sys, time
runs = int(sys.argv[1])

def whole(cmd):
    """Best and mean wall time of the whole process over `runs`, and its last output with
    `run_seconds` (where it has one) the best of the runs'."""
    times, outs = [], []
    for _ in range(runs):
        t0 = time.perf_counter()
        outs.append(json.loads(
            subprocess.run(cmd, check=True, capture_output=True, text=True).stdout))
        times.append(time.perf_counter() - t0)
    out = outs[-1]
    if "run_seconds" in out:
        out["run_seconds"] = min(o["run_seconds"] for o in outs)
    return out, min(times), sum(times) / len(times)

def host_sim(*args):
    return ["target/peak/host-sim", "--json", "simulate", *args]

failed = []
def agree(what, ours, theirs, within):
    diff = abs(ours - theirs)
    print(f"  final stretch  host-sim {ours:.15f}  peer {theirs:.15f}  |diff| {diff:.1e} "
          f"(within {within:.0e})")
    if not diff <= within:
        failed.append(what)

print("DOP853: reference scene, 7000 V + 200 V at 30 Hz, 10 s, output every 1/64 period, 1e-12")
ours, best, mean = whole(host_sim("--bias-volts", "7000", "--ac-volts", "200", "--ac-hz",
                                  "30", "--duration-seconds", "10"))
peer = json.loads(subprocess.run(
    [sys.executable, "scripts/peers/solve.py", "--runs", str(runs), "numbalsoda-dop853",
     "7000", "200", "30", "0", "10", repr(ours["step_seconds"]), "equilibrium", "1e-12"],
    check=True, capture_output=True, text=True).stdout)
agree("dop853", ours["final"]["stretch"], peer["final_stretch"], 1e-8)
print(f"  {'':34}{'best ms':>10}{'mean ms':>10}")
print(f"  {'host-sim simulate, whole process':34}{best * 1e3:10.2f}{mean * 1e3:10.2f}")
print(f"  {'  of which the solve (in-process)':34}{ours['run_seconds'] * 1e3:10.2f}")
print(f"  {'numbalsoda dop853, in-process':34}{peer['best_seconds'] * 1e3:10.2f}"
      f"{peer['mean_seconds'] * 1e3:10.2f}")
print(f"  ratio (best, whole process / peer in-process): {best / peer['best_seconds']:.2f} "
      f"(issue 63's goal ≤ 1.0), {peer['samples']} samples each")

print("BDF: damped scene, c = 10 N·s, 7000 V + 200 V at 30 Hz from the pre-stretch, 1 s, 1e-10")
args = ["--bias-volts", "7000", "--ac-volts", "200", "--ac-hz", "30", "--duration-seconds", "1",
        "--damping", "10", "--start", "prestretch", "--method", "reference-bdf"]
ours, best, mean = whole(host_sim(*args))
cvode = ["target/cvode_scene", "7000", "200", "30", "10", "1", repr(ours["step_seconds"]),
         "1e-10", "1"]
peer, peer_best, peer_mean = whole(cvode)
agree("bdf", ours["final"]["stretch"], peer["final_stretch"], 1e-8)
dop = whole(host_sim(*args[:-2], "--method", "reference"))[0]
print(f"  (DOP853 at 1e-12 on it: {dop['final']['stretch']:.15f}, {dop['run_seconds'] * 1e3:.1f} ms "
      "in-process: BDF is the right choice)")
print(f"  {'':34}{'best ms':>10}{'mean ms':>10}")
print(f"  {'host-sim reference-bdf, whole':34}{best * 1e3:10.2f}{mean * 1e3:10.2f}")
print(f"  {'  of which the solve (in-process)':34}{ours['run_seconds'] * 1e3:10.2f}")
print(f"  {'CVODE BDF, whole process':34}{peer_best * 1e3:10.2f}{peer_mean * 1e3:10.2f}")
print(f"  ratio (best, whole processes): {best / peer_best:.2f} (goal ≤ 2), CVODE took "
      f"{peer['steps']} steps")

print("The stiff methods side by side (issue 45), from the pre-stretch, 1 s, 1e-10: whole "
      "process best and mean, the solve in-process, and the final stretch")
cases = [("damped, c = 10 N·s, 7000 V + 200 V at 30 Hz", "7000", "200", "30", "10"),
         ("stiff, c = 10,000 N·s, 5912.84 V", "5912.84", "0", "30", "10000")]
print(f"  {'scene':46}{'method':18}{'best ms':>9}{'mean ms':>9}{'solve ms':>9}  final stretch")
for name, bias, ac, hz, damping in cases:
    args = ["--bias-volts", bias, "--ac-volts", ac, "--ac-hz", hz, "--duration-seconds", "1",
            "--damping", damping, "--start", "prestretch"]
    finals = {}
    for method in ["reference-radau", "reference-bdf"]:
        ours, best, mean = whole(host_sim(*args, "--method", method))
        finals[method] = ours["final"]["stretch"]
        print(f"  {name:46}{method:18}{best * 1e3:9.2f}{mean * 1e3:9.2f}"
              f"{ours['run_seconds'] * 1e3:9.2f}  {finals[method]:.12f}")
    peer, peer_best, peer_mean = whole(["target/cvode_scene", bias, ac, hz, damping, "1",
                                        repr(ours["step_seconds"]), "1e-10", "1"])
    print(f"  {name:46}{'CVODE BDF':18}{peer_best * 1e3:9.2f}{peer_mean * 1e3:9.2f}"
          f"{peer['best_seconds'] * 1e3:9.2f}  {peer['final_stretch']:.12f} "
          f"({peer['steps']} steps)")
    for method, final in finals.items():
        agree(f"{method} on {name}", final, peer["final_stretch"], 1e-8)
if failed:
    sys.exit(f"the final states disagree: {failed}")
PY
