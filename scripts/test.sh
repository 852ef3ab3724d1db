#!/usr/bin/env bash
# Every test of raylane, as CI runs it (.ci/run calls this script).
#
#   ./scripts/test.sh
#
# Formatting, clippy, the host test suite (with the test vectors), the checker over every
# vector file with every method at every lane width, and a no_std build for Cortex-M.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n== %s\n' "$*"; }
start=$SECONDS

step "toolchain targets"
rustup target add thumbv7em-none-eabihf >/dev/null

step "format and lints"
cargo fmt --all -- --check
cargo clippy --quiet --all-targets --features vectors -- -D warnings

step "host test suite"
cargo test --quiet --features vectors

step "checker: every method, every lane width"
cargo build --quiet --release --features vectors --example check
for method in $(./target/release/examples/check --list); do
  for lanes in 1 4 8 16; do
    printf '%-16s x%-3s' "$method" "$lanes"
    ./target/release/examples/check --method "$method" --lanes "$lanes" tests/vectors/*.txt | tail -n 1
  done
done
printf '%-20s' "recommended"
./target/release/examples/check tests/vectors/*.txt | tail -n 1

step "no_std library for Cortex-M4F (thumbv7em-none-eabihf)"
cargo build --quiet --lib --release --target thumbv7em-none-eabihf

printf '\nall tests passed in %ss\n' "$((SECONDS - start))"
