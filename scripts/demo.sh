#!/usr/bin/env bash
# Every kernel on the test vectors (exact references), and the operation counts. (The main
# job, the renderer, is `cargo run --release --example render`.)
#
#   ./scripts/demo.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --quiet --release --example check --example opcount
for method in quadratic geometric robust focal plane cramer moller watertight; do
  printf '\n== %s (cases outside its documented limits are counted, not compared)\n' "$method"
  ./target/release/examples/check --method "$method" tests/vectors/*.txt
done
printf '\n== every kernel, operations per lane per test (measured with the counting lane)\n\n'
./target/release/examples/opcount
