#!/usr/bin/env bash
# The cargo-fuzz targets (fuzz/): libFuzzer on the table parser and on the controller's boot
# and ticks, each for FUZZ_SECONDS (default 30), on stable Rust with `--sanitizer none`
# (no sanitizer: panics and failed assertions are what it finds). Installs cargo-fuzz when
# missing. Seeds: fuzz/seeds/<target>/; the corpus grows in fuzz/corpus/ (not committed).
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
seconds="${FUZZ_SECONDS:-30}"
if ! command -v cargo-fuzz >/dev/null; then
    cargo install --locked cargo-fuzz --version 0.13.2
fi
mkdir -p target
for target in table_parse controller image_and_commands; do
    mkdir -p "corpus/$target"
    cp -n "seeds/$target/"* "corpus/$target/"
    echo "== cargo fuzz: $target for $seconds s"
    status=0
    cargo fuzz run -s none "$target" "corpus/$target" -- -max_total_time="$seconds" \
        >"target/$target.log" 2>&1 || status=$?
    if [ "$status" != 0 ]; then
        tail -40 "target/$target.log"
        echo "cargo fuzz $target failed (status $status): a build error above, or a finding" \
            "with its input in fuzz/artifacts/$target/" >&2
        exit "$status"
    fi
    grep -E '^Done' "target/$target.log"
done
