#!/usr/bin/env bash
# Every check CI runs, from a fresh machine: installs what it needs, then formats, lints
# (host and Cortex-M4F target), builds the core for the target, and runs all tests.
set -euo pipefail
cd "$(dirname "$0")/.."

TARGET=thumbv7em-none-eabihf
step() { printf '\n== %s\n' "$*"; }

step "toolchain (rust-toolchain.toml) and the $TARGET target"
rustup show active-toolchain
rustup component add clippy rustfmt
rustup target add "$TARGET"

step "format"
cargo fmt --all -- --check

step "clippy, host"
cargo clippy --locked --workspace --all-targets -- -D warnings

step "clippy, target (core with defmt)"
cargo clippy --locked -p de-resonator --target "$TARGET" --features defmt -- -D warnings

step "build the no_std core for $TARGET"
cargo build --locked -p de-resonator --target "$TARGET" --release
cargo build --locked -p de-resonator --target "$TARGET" --release --features defmt

step "tests (core integration tests, host-sim unit and CLI tests)"
cargo test --locked --workspace
