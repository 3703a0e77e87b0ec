#!/usr/bin/env bash
# Cargo runner: the ELF in QEMU's netduinoplus2 (STM32F405), defmt frames over semihosting
# decoded by defmt-print (a build without defmt runs alone). Exits with the firmware's
# status (QEMU's), not the decoder's. Environment:
#   QEMU_IMAGE=FILE     the configuration image, loaded at 0x080E0000 (flash sector 11); a
#                       relative path is taken from where cargo was started (the caller's
#                       folder, as QEMU_CALLER_DIR says when set)
#   QEMU_SERIAL1=SPEC   USART2, the command port: a -serial spec (default: null), e.g.
#                       unix:/tmp/fw.sock,server=on,wait=on  or  tcp:127.0.0.1:4444,server=on
#   QEMU_SERIAL0=SPEC   USART1, the telemetry stream (default: null), e.g.
#                       unix:/tmp/fw-stream.sock,server=on,wait=off
#   QEMU_ICOUNT=1       -icount shift=0,sleep=off (one nanosecond of virtual time an
#                       instruction, deterministic; QEMU-STM32F405.md §2)
#   QEMU_EXTRA="..."    more QEMU arguments (e.g. -d trace:memory_region_ops_write -D FILE)
#   QEMU_TIMEOUT=S      host seconds before QEMU is stopped (default: none; the test
#                       scripts set one)
#   QEMU_ARGS=WORD      a semihosting argument for the firmware (e.g. busy-idle)
set -uo pipefail
elf="$1"
extra=()
if [ "${QEMU_ICOUNT:-0}" = 1 ]; then extra+=(-icount shift=0,sleep=off); fi
if [ -n "${QEMU_IMAGE:-}" ]; then
    image="$QEMU_IMAGE"
    case "$image" in /*) ;; *) image="${QEMU_CALLER_DIR:-$PWD}/$image" ;; esac
    if [ ! -f "$image" ]; then echo "qemu-run.sh: no image at $image (QEMU_IMAGE)" >&2; exit 2; fi
    extra+=(-device "loader,file=${image},addr=0x080E0000")
fi
# shellcheck disable=SC2206
if [ -n "${QEMU_EXTRA:-}" ]; then extra+=($QEMU_EXTRA); fi
limit=()
# --foreground: timeout stays in the caller's process group, so a group kill (scripts/qemu.sh)
# reaches QEMU.
if [ -n "${QEMU_TIMEOUT:-}" ]; then limit=(timeout --foreground "$QEMU_TIMEOUT"); fi
qemu() {
    "${limit[@]}" qemu-system-arm -M netduinoplus2 -nographic -monitor none \
        -serial "${QEMU_SERIAL0:-null}" -serial "${QEMU_SERIAL1:-null}" \
        -semihosting-config "enable=on,target=native${QEMU_ARGS:+,arg=firmware,arg=$QEMU_ARGS}" \
        "${extra[@]}" -kernel "$elf"
}
# A build without defmt (no .defmt section) has no log to decode: its exit status says all.
if ! size -A "$elf" | grep -q '^\.defmt '; then
    qemu
    exit $?
fi
qemu | defmt-print -e "$elf" --log-format "{L} {s}"
exit "${PIPESTATUS[0]}"
