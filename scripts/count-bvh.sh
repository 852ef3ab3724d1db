#!/usr/bin/env bash
# Executed instructions of the firmware `bvh` (targets/src/bin/bvh.rs) on the Cortex-M0
# (microbit), M4F (mps2-an386) and M33 (mps2-an505) under QEMU, counted exactly by the TCG
# plugin in targets/plugin between the marker functions bvh_begin and bvh_end: one 64×48 frame
# of primary rays through the vendored bunny's baked tree (3,674 triangles, in flash) at 1
# lane, and on the M4F and M33 at 4, 8 and 16 lanes (shading included). Needs what
# scripts/count-fw.sh installs.
#
#   ./scripts/count-bvh.sh          prints one line per board and window
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
plugin=$("$root/targets/plugin/build.sh")
for t in cortex-m0:thumbv6m-none-eabi:microbit cortex-m4f:thumbv7em-none-eabihf:mps2-an386 cortex-m33:thumbv8m.main-none-eabihf:mps2-an505; do
  IFS=: read -r name target board <<< "$t"
  (cd "$root/targets" && cargo build --quiet --release --target "$target" --bin bvh)
  elf="$root/targets/target/$target/release/bvh"
  addr() { arm-none-eabi-nm "$elf" | awk -v s="$1" '$3 == s { print $1 }'; }
  err=$(mktemp)
  timeout 600 qemu-system-arm -machine "$board" -nographic \
    -semihosting-config enable=on,target=native -kernel "$elf" \
    -plugin "$plugin,start=0x$(addr bvh_begin),stop=0x$(addr bvh_end)" > /dev/null 2> "$err"
  rm -f "$root/targets/target/bvh.ppm"
  awk -v n="$name" '$1 == "window" { w[$2 + 0] = $3 }
    END {
      want = (n == "cortex-m0") ? 1 : 4
      if (length(w) != want) { print n ": expected " want " windows, got " length(w) > "/dev/stderr"; exit 1 }
      split("1 4 8 16", l, " ")
      for (i = 1; i <= want; i++)
        printf "%s: x%s frame %d instructions, %.0f per primary ray (3072 rays, 979 hit)\n", n, l[i], w[i], w[i] / 3072
    }' "$err"
  rm -f "$err"
done
