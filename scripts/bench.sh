#!/usr/bin/env bash
# raylane's benchmarks: side by side with its peers, every kernel at every lane width, and the
# deterministic instruction counts (x86-64-v3 under callgrind, Cortex-M4F under QEMU).
#
#   ./scripts/bench.sh              all of it (about 25 minutes on 2 cores, builds included)
#   ./scripts/bench.sh compare      raylane, parry3d, bevy, obvhs and Embree on the same scenes
#   ./scripts/bench.sh kernels      every kernel × lane width × scene
#   ./scripts/bench.sh counts       instructions per test: x86-64-v3 and Cortex-M4F
#   ./scripts/bench.sh scenes       meshes of 10^3..10^6 triangles and 10^5 spheres: primary,
#                                   diffuse and shadow rays; Embree, obvhs, parry3d, raylane
#                                   (a plain timed example, medians of a few runs; ~10 minutes)
#
# Installs what it needs on Debian (libembree-dev for Embree, valgrind, QEMU and the ARM
# binutils for the counts). The timed benches are built as users build them, with no
# `target-cpu` (in target/bench): raylane picks its SIMD level when it runs, as Embree picks
# its ISA; the header of each summary names the level. `NATIVE=1 ./scripts/bench.sh ...`
# builds for this machine's CPU instead (`-C target-cpu=native`, in target/bench-native), the
# reference the default build is compared with. Each summary is printed after criterion's
# report and kept in target/bench/*.md (*-native.md for NATIVE=1).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
out="$root/target/bench"
mkdir -p "$out"
what=${1:-all}

need=()
[ -e /usr/include/embree3/rtcore.h ] || need+=(libembree-dev)
if [ ${#need[@]} -gt 0 ]; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "installing: ${need[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi

flags=""; tdir="$root/target/bench"; suffix=""
if [ -n "${NATIVE:-}" ]; then flags="-C target-cpu=native"; tdir="$root/target/bench-native"; suffix="-native"; fi

timed() { # timed NAME ARGS...: one criterion bench, its summary kept in target/bench/NAME.md
  local name=$1; shift
  RUSTFLAGS="$flags" cargo bench --quiet -p raylane-bench --target-dir "$tdir" \
    --bench "$name" "$@" | tee "$out/$name$suffix.log"
  sed -n '/^## /,$p' "$out/$name$suffix.log" > "$out/$name$suffix.md"
}

scenes() { # the BVH benchmark (benches/examples/scenes.rs), its tables kept in target/bench/scenes.md
  RUSTFLAGS="$flags" cargo run --quiet --release -p raylane-bench --features peers \
    --target-dir "$tdir" --example scenes -- "$@" | tee "$out/scenes$suffix.log"
  sed -n '/^## /,$p' "$out/scenes$suffix.log" > "$out/scenes$suffix.md"
}

case $what in
  all | compare) timed compare --features peers ;;&
  all | scenes) shift || true; scenes "$@" ;;&
  all | kernels) timed kernels ;;&
  all | counts)
    "$root/scripts/count-x86.sh" | tee "$out/count-x86-64-v3.md"
    "$root/scripts/count-m4f.sh" | tee "$out/count-cortex-m4f.md"
    ;;
  all | compare | kernels | scenes) ;;
  *) echo "usage: $0 [all|compare|kernels|counts|scenes [--only NAME]...]" >&2; exit 2 ;;
esac
echo "summaries: $out/*.md"
