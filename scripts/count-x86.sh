#!/usr/bin/env bash
# Instructions per ray–primitive test of every raylane kernel on x86-64-v3, counted exactly by
# valgrind's callgrind (which cannot decode AVX-512, hence x86-64-v3: AVX2 + FMA).
#
#   ./scripts/count-x86.sh            prints the Markdown table (also kept in target/count/x86-64-v3.md)
#
# The `count` example (benches/examples/count.rs) runs every kernel × lane width × packet shape
# × ray set as one call of an out-of-line frame function, once over 64 primitives and once over
# none. Callgrind collects only inside those calls (--toggle-collect) and dumps after each one
# (--dump-after), so dump k holds exactly the instructions of call k; the difference between
# the two calls of a configuration, over its tests, is the cost of one test. The table puts
# beside it the minimum the op count implies: (FP operations + primitive loads) / lanes.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
out="$root/target/count"
mkdir -p "$out"

if ! command -v valgrind >/dev/null; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends valgrind >/dev/null
fi

RUSTFLAGS="-C target-cpu=x86-64-v3" cargo build --quiet --release -p raylane-bench --example count \
  --target-dir "$root/target/count-x86-64-v3"
bin="$root/target/count-x86-64-v3/release/examples/count"

dir=$(mktemp -d "$out/callgrind.XXXXXX")
trap 'rm -rf "$dir"' EXIT
valgrind --tool=callgrind --collect-atstart=no \
  --toggle-collect='*packets_frame*' --toggle-collect='*rays_frame*' \
  --dump-after='raylane_bench::packets_frame' --dump-after='raylane_bench::rays_frame' \
  --callgrind-out-file="$dir/cg.out" "$bin" measure > "$dir/manifest.txt" 2> "$dir/valgrind.log" \
  || { cat "$dir/valgrind.log" >&2; exit 1; }

# Line k of the manifest names call k; dump k holds its instructions.
calls=$(wc -l < "$dir/manifest.txt")
k=0
while read -r line; do
  k=$((k + 1))
  n=$(awk '$1 == "totals:" { print $2 }' "$dir/cg.out.$k")
  echo "$line ${n:?no totals in dump $k}"
done < "$dir/manifest.txt" > "$dir/counts.txt"
[ "$k" -eq "$calls" ] && [ -e "$dir/cg.out.$calls" ] || { echo "dumps do not match the calls" >&2; exit 1; }
cp "$dir/counts.txt" "$out/x86-64-v3.txt"

cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')
"$bin" table "$out/x86-64-v3.txt" \
  "x86-64-v3 (AVX2, callgrind; $cpu; valgrind $(valgrind --version | sed 's/valgrind-//'))" \
  | tee "$out/x86-64-v3.md"
