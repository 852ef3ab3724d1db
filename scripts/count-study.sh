#!/usr/bin/env bash
# Executed instructions per ray–primitive test of every method of the op-count study
# (raylane_lab::study, the study table of docs/opcounts.md), on x86-64-v3 (valgrind's callgrind,
# 8 lanes) and on a Cortex-M4F (QEMU's mps2-an386 with the TCG plugin targets/plugin/insncount.c,
# scalar lane). From scratch on Debian bookworm:
#
#   ./scripts/count-study.sh     rewrites docs/study-insns.txt (the counts `cargo run --example
#                                opcount` prints; `-- --write` then puts them in the README)
#
# Both sides run the same timed loop, raylane_lab::study::repeat (see its docs): per method and
# path (miss, hit) one call over 64 tests and one over none; (count over 64 − count over none)
# / (64 · lanes) is one test's instructions, the loop's bookkeeping included and the per-ray
# setup and precomputation excluded. Counts are exact and repeatable for a given compiler:
# the file's header records the versions they were measured with.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
out="$root/target/count"
mkdir -p "$out"

need=()
command -v valgrind >/dev/null || need+=(valgrind)
command -v qemu-system-arm >/dev/null || need+=(qemu-system-arm)
command -v arm-none-eabi-nm >/dev/null || need+=(binutils-arm-none-eabi)
if [ ${#need[@]} -gt 0 ]; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
rustup target add thumbv7em-none-eabihf 2>&1 | grep -v "is up to date" || true

# x86-64-v3 (valgrind cannot decode AVX-512): the opcount example's --measure mode, one
# callgrind dump per call of raylane_lab::study::repeat.
RUSTFLAGS="-C target-cpu=x86-64-v3" cargo build --quiet --release --example opcount \
  --target-dir "$root/target/count-x86-64-v3"
bin="$root/target/count-x86-64-v3/release/examples/opcount"
dir=$(mktemp -d "$out/study.XXXXXX")
trap 'rm -rf "$dir"' EXIT
valgrind --tool=callgrind --collect-atstart=no \
  --toggle-collect='raylane_lab::study::repeat' --dump-after='raylane_lab::study::repeat' \
  --callgrind-out-file="$dir/cg.out" "$bin" --measure > "$dir/manifest.txt" 2> "$dir/valgrind.log" \
  || { cat "$dir/valgrind.log" >&2; exit 1; }
calls=$(grep -c '^cfg' "$dir/manifest.txt")
k=0
while read -r line; do
  k=$((k + 1))
  n=$(awk '$1 == "totals:" { print $2 }' "$dir/cg.out.$k")
  echo "$line ${n:?no totals in dump $k}"
done < <(grep '^cfg' "$dir/manifest.txt") > "$out/study-x86-64-v3.txt"
[ "$k" -eq "$calls" ] && [ ! -e "$dir/cg.out.$((calls + 1))" ] \
  || { echo "callgrind dumps do not match the calls" >&2; exit 1; }

# Cortex-M4F: the firmware `study` between its markers study_begin and study_end.
plugin=$("$root/targets/plugin/build.sh")
(cd "$root/targets" && cargo build --quiet --release --target thumbv7em-none-eabihf --bin study)
elf="$root/targets/target/thumbv7em-none-eabihf/release/study"
addr() { arm-none-eabi-nm "$elf" | awk -v s="$1" '$3 == s { print $1 }'; }
begin=$(addr study_begin); end=$(addr study_end)
[ -n "$begin" ] && [ -n "$end" ] || { echo "no study_begin/study_end in $elf" >&2; exit 1; }
timeout 600 qemu-system-arm -machine mps2-an386 -nographic \
  -semihosting-config enable=on,target=native -kernel "$elf" \
  -plugin "$plugin,start=0x$begin,stop=0x$end" > "$dir/m4f.stdout" 2> "$dir/m4f.stderr" \
  || { cat "$dir/m4f.stdout" "$dir/m4f.stderr" >&2; echo "the firmware failed" >&2; exit 1; }
cfgs=$(grep -c '^cfg' "$dir/m4f.stdout"); wins=$(grep -c '^window' "$dir/m4f.stderr")
[ "$cfgs" -eq "$wins" ] && [ "$cfgs" -eq "$calls" ] \
  || { echo "$cfgs configurations, $wins windows, $calls on x86" >&2; exit 1; }
paste -d' ' <(grep '^cfg' "$dir/m4f.stdout") <(awk '$1 == "window" { print $3 }' "$dir/m4f.stderr") \
  > "$out/study-cortex-m4f.txt"

# `cfg SHAPE METHOD PATH LANES TESTS INSNS`, the call over 64 tests before the one over none.
# Keyed by shape, method and path (the order is the study's, raylane_lab::study::KERNELS, the
# registry's); the report reads docs/study-insns.txt by those names, in any order.
per_test() {
  awk -v target="$1" '
    $6 > 0 { key = $2 " " $3 " " $4; full[key] = $7; tests[key] = $6 * $5; order[++n] = key }
    $6 == 0 { empty[$2 " " $3 " " $4] = $7 }
    END { for (i = 1; i <= n; i++) { k = order[i]
            printf "%s %s %.2f\n", target, k, (full[k] - empty[k]) / tests[k] } }' "$2"
}
data="$root/docs/study-insns.txt"
{
  echo "# Executed instructions per ray–primitive test of each method of the op-count study:"
  echo "# target shape method path instructions. Written by scripts/count-study.sh (do not edit);"
  echo "# read by \`cargo run --example opcount\` for the README's study table."
  echo "# x86-64-v3: 8 lanes (f32x8), $(rustc -V), -C target-cpu=x86-64-v3, release,"
  echo "#   valgrind $(valgrind --version | sed 's/valgrind-//') (callgrind)."
  echo "# cortex-m4f: scalar f32, $(rustc -V), thumbv7em-none-eabihf, opt-level s, LTO,"
  echo "#   QEMU $(qemu-system-arm --version | awk 'NR==1 { print $4 }') mps2-an386, TCG plugin."
  per_test x86-64-v3 "$out/study-x86-64-v3.txt"
  per_test cortex-m4f "$out/study-cortex-m4f.txt"
} > "$data"
cat "$data"
