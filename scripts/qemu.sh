#!/usr/bin/env bash
# The firmware under QEMU with an image and a console, from the repository's root, in one
# command: builds the firmware (QEMU build) and host-sim, makes an image unless given one,
# starts QEMU (netduinoplus2) with the command port (USART2) on a Unix socket, and opens
# `host-sim console` on it. No time limit; Ctrl-C or the console's end (Ctrl-D) stops QEMU.
#
# Usage: scripts/qemu.sh [--image FILE] [--socket PATH] [--no-console] [--pty] [-- CONSOLE-ARGS...]
#   --image FILE   the configuration image to flash (default: the reference device at 44 Hz,
#                  made by `host-sim image`: it waits for `start`)
#   --socket PATH  the command port's socket (default: target/qemu/fw.sock); the telemetry
#                  stream (USART1) is served beside it, at PATH with `-stream` before its
#                  extension (target/qemu/fw-stream.sock): `-- --record run.csv
#                  --stream-unix target/qemu/fw-stream.sock` records it
#   --no-console   serve the socket only (talk to it with `host-sim console --unix PATH`),
#                  until Ctrl-C
#   --pty          the command port on a pseudo-terminal, as a board's USB serial port:
#                  prints its path for any terminal program (`picocom /dev/pts/N`), until
#                  Ctrl-C
#   after --       more arguments for `host-sim console` (e.g. --script FILE, --json)
# Environment: QEMU_TIMEOUT=S stops QEMU after S seconds (none by default); HOST_SIM=path
# uses that host-sim binary rather than building the release one.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
image="" socket="$root/target/qemu/fw.sock" console=1 pty=0 console_args=()
while [ $# -gt 0 ]; do
    case "$1" in
        --image) image="$(realpath "${2:?--image needs a file}")"; shift 2 ;;
        --socket) socket="$(realpath -m "${2:?--socket needs a path}")"; shift 2 ;;
        --no-console) console=0; shift ;;
        --pty) console=0 pty=1; shift ;;
        --) shift; console_args=("$@"); break ;;
        -h|--help) sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "qemu.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
    esac
done
command -v qemu-system-arm >/dev/null || { echo "qemu.sh: install qemu-system-arm (apt-get install qemu-system-arm)" >&2; exit 2; }
mkdir -p "$root/target/qemu" "$(dirname "$socket")"
echo "building host-sim and the firmware (QEMU build)..." >&2
if [ -n "${HOST_SIM:-}" ]; then
    host_sim="$(realpath "$HOST_SIM")"
else
    cargo build --locked --release -q -p host-sim --manifest-path "$root/Cargo.toml"
    host_sim="$root/target/release/host-sim"
fi
(cd "$root/firmware" && cargo build --locked --release -q --bin firmware)
elf="$root/firmware/target/thumbv7em-none-eabihf/release/firmware"
if [ -z "$image" ]; then
    image="$root/target/qemu/reference.img"
    "$host_sim" image --target-hz 44 --out "$image" >/dev/null
fi
"$host_sim" image --check "$image" >/dev/null || { echo "qemu.sh: the firmware would refuse $image (host-sim image --check $image)" >&2; }
stream="${socket%.sock}-stream.sock"
rm -f "$socket" "$stream"
log="$root/target/qemu/firmware.log"
# QEMU waits for the console to connect (wait=on): nothing is missed, the start-up line first.
# In a process group of its own (setsid): the runner, QEMU and the log decoder stop together.
port="unix:$socket,server=on,wait=on"
[ "$pty" = 1 ] && port="pty"
(cd "$root/firmware" && QEMU_IMAGE="$image" QEMU_SERIAL1="$port" \
    QEMU_SERIAL0="unix:$stream,server=on,wait=off" \
    exec setsid ./qemu-run.sh "$elf") >"$log" 2>&1 &
runner=$!
stop() {
    kill -TERM -- "-$runner" 2>/dev/null || true
    wait "$runner" 2>/dev/null || true
    rm -f "$socket" "$stream"
}
trap stop EXIT
trap 'exit 130' INT TERM
if [ "$pty" = 1 ]; then
    # QEMU's "char device redirected to /dev/pts/N" goes to the log's decoder: the pty is
    # read off QEMU's open /dev/ptmx instead (its fdinfo names the terminal's index).
    dev=""
    for _ in $(seq 100); do
        qemu_pid="$(pgrep -g "$runner" -x qemu-system-arm | head -1 || true)"
        if [ -n "$qemu_pid" ]; then
            for fd in /proc/"$qemu_pid"/fd/*; do
                if [ "$(readlink "$fd")" = /dev/ptmx ]; then
                    index="$(sed -n 's/^tty-index:[[:space:]]*//p' /proc/"$qemu_pid"/fdinfo/"${fd##*/}")"
                    [ -n "$index" ] && dev="/dev/pts/$index"
                fi
            done
        fi
        [ -n "$dev" ] && break
        sleep 0.1
    done
    [ -n "$dev" ] || { cat "$log" >&2; echo "qemu.sh: QEMU opened no pty" >&2; exit 1; }
    echo "firmware under QEMU: image $image, log $log" >&2
    echo "the command port: $dev (picocom $dev, screen $dev; Ctrl-C here stops QEMU)" >&2
    echo "$dev"
    wait "$runner"
    exit 0
fi
for _ in $(seq 100); do [ -S "$socket" ] && break; sleep 0.1; done
[ -S "$socket" ] || { cat "$log" >&2; echo "qemu.sh: QEMU did not open $socket" >&2; exit 1; }
echo "firmware under QEMU: image $image, command port $socket, telemetry stream $stream, log $log" >&2
if [ "$console" = 1 ]; then
    "$host_sim" console --unix "$socket" "${console_args[@]}"
else
    echo "serving: host-sim console --unix $socket (Ctrl-C stops QEMU)" >&2
    wait "$runner"
fi
