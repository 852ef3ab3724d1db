#!/usr/bin/env bash
# Instructions per ray through a whole scene on x86-64-v3, raylane's BVH beside Embree,
# counted exactly by valgrind's callgrind (which cannot decode AVX-512, hence x86-64-v3; Embree
# picks its AVX2 kernels under it).
#
#   ./scripts/count-scenes.sh            prints the Markdown table (also kept in target/count/scenes.md)
#   ./scripts/count-scenes.sh --default  the same for a default build (no target-cpu: what users
#                                        ship), which valgrind runs at the AVX2 level (raylane::simd)
#
# The `count_scenes` example (benches/examples/count_scenes.rs) runs each frame (primary,
# diffuse and shadow rays of the vendored bunny) as one call of an out-of-line function;
# callgrind collects only inside those calls and dumps after each one.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
out="$root/target/count"
mkdir -p "$out"
need=()
command -v valgrind >/dev/null || need+=(valgrind)
dpkg -s libembree-dev >/dev/null 2>&1 || need+=(libembree-dev)
if [ "${#need[@]}" -gt 0 ]; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi

build=x86-64-v3; flags="-C target-cpu=x86-64-v3"; tdir=count-x86-64-v3
if [ "${1:-}" = --default ]; then build=default; flags=""; tdir=count-default; fi
RUSTFLAGS="$flags" cargo build --quiet --release -p raylane-bench --features peers \
  --example count_scenes --target-dir "$root/target/$tdir"
bin="$root/target/$tdir/release/examples/count_scenes"

dir=$(mktemp -d "$out/callgrind.XXXXXX")
trap 'rm -rf "$dir"' EXIT
valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*scene_frame*' \
  --dump-after='count_scenes::scene_frame' \
  --callgrind-out-file="$dir/cg.out" "$bin" measure > "$dir/manifest.txt" 2> "$dir/valgrind.log" \
  || { cat "$dir/valgrind.log" >&2; exit 1; }
k=0
while read -r line; do
  k=$((k + 1))
  n=$(awk '$1 == "totals:" { print $2 }' "$dir/cg.out.$k")
  echo "$line ${n:?no totals in dump $k}"
done < "$dir/manifest.txt" > "$out/scenes-$build.txt"
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')
what="x86-64-v3 build"; [ "$build" = default ] && what="default build at the AVX2 level"
"$bin" table "$out/scenes-$build.txt" "$what ($cpu; valgrind $(valgrind --version | sed 's/valgrind-//'))" \
  | tee "$out/scenes-$build.md"
