#!/usr/bin/env bash
# The cargo-fuzz targets (fuzz/): libFuzzer on the table parser and on the controller's boot
# and ticks, each for FUZZ_SECONDS (default 30), on stable Rust with `--sanitizer none`
# (no sanitizer: panics and failed assertions are what it finds). Installs cargo-fuzz when
# missing. Seeds: fuzz/seeds/<target>/; the corpus grows in fuzz/corpus/ (not committed).
# FUZZ_PARALLEL=1 runs the targets side by side (CI); the long campaigns run them one by one.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
seconds="${FUZZ_SECONDS:-30}"
if ! command -v cargo-fuzz >/dev/null; then
    cargo install --locked cargo-fuzz --version 0.13.2
fi
mkdir -p target
targets=(table_parse controller image_and_commands)
# Each target's run and its outcome (a finding's input in fuzz/artifacts/<target>/).
run() {
    local target=$1
    mkdir -p "corpus/$target"
    cp -n "seeds/$target/"* "corpus/$target/"
    cargo fuzz run -s none "$target" "corpus/$target" -- -max_total_time="$seconds" \
        >"target/$target.log" 2>&1
}
report() {
    local target=$1 status=$2
    if [ "$status" != 0 ]; then
        tail -40 "target/$target.log"
        echo "cargo fuzz $target failed (status $status): a build error above, or a finding" \
            "with its input in fuzz/artifacts/$target/" >&2
        exit "$status"
    fi
    grep -E '^Done' "target/$target.log"
}
if [ "${FUZZ_PARALLEL:-0}" = 1 ]; then
    # All targets at once, after one build of them all (CI: the time is the longest run's,
    # each run's inputs fewer where they share the cores).
    echo "== cargo fuzz: build, then ${targets[*]} at once for $seconds s"
    cargo fuzz build -s none >target/build.log 2>&1 || { tail -40 target/build.log; exit 1; }
    pids=()
    for target in "${targets[@]}"; do
        run "$target" &
        pids+=($!)
    done
    for i in "${!targets[@]}"; do
        status=0
        wait "${pids[$i]}" || status=$?
        report "${targets[$i]}" "$status"
    done
else
    for target in "${targets[@]}"; do
        echo "== cargo fuzz: $target for $seconds s"
        status=0
        run "$target" || status=$?
        report "$target" "$status"
    done
fi
