#!/usr/bin/env bash
# Cargo runner: the ELF in QEMU's netduinoplus2 (STM32F405), defmt frames over semihosting
# decoded by defmt-print (a build without defmt runs alone). Exits with the firmware's
# status (QEMU's), not the decoder's.
# QEMU_ICOUNT=1 runs with -icount shift=0 (one nanosecond of virtual time per instruction).
set -uo pipefail
elf="$1"
extra=()
if [ "${QEMU_ICOUNT:-0}" = 1 ]; then extra=(-icount shift=0); fi
qemu() {
    timeout "${QEMU_TIMEOUT:-60}" qemu-system-arm -M netduinoplus2 -nographic -monitor none \
        -serial null -semihosting-config enable=on,target=native "${extra[@]}" -kernel "$elf"
}
# A build without defmt (no .defmt section) has no log to decode: its exit status says all.
if ! size -A "$elf" | grep -q '^\.defmt '; then
    qemu
    exit $?
fi
qemu | defmt-print -e "$elf" --log-format "{L} {s}"
exit "${PIPESTATUS[0]}"
