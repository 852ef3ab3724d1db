#!/usr/bin/env bash
# Executed instructions per ray–primitive test of every raylane kernel on a Cortex-M4F
# (QEMU's mps2-an386), counted exactly by a TCG plugin. From scratch on Debian bookworm:
#
#   ./scripts/count-m4f.sh            prints the Markdown table (also kept in target/count/cortex-m4f.md)
#
# 1. Installs QEMU, the ARM binutils and the thumbv7em target if missing.
# 2. Builds the plugin (targets/plugin/build.sh: qemu-plugin.h from Debian's qemu source).
# 3. Builds the firmware `bench` (targets/src/bin/bench.rs): every kernel over the host's
#    scene, each frame once over 64 primitives and once over none, between the marker
#    functions bench_begin and bench_end.
# 4. Runs it under QEMU with the plugin counting each marker window, checks that the firmware
#    built the host's scene (digests), and prints per test (window over 64 − window over
#    none) / tests beside the minimum the op count implies (FP operations + loads).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
out="$root/target/count"
mkdir -p "$out"

need=()
command -v qemu-system-arm >/dev/null || need+=(qemu-system-arm)
command -v arm-none-eabi-nm >/dev/null || need+=(binutils-arm-none-eabi)
if [ ${#need[@]} -gt 0 ]; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
rustup target add thumbv7em-none-eabihf 2>&1 | grep -v "is up to date" || true

plugin=$("$root/targets/plugin/build.sh")
(cd "$root/targets" && cargo build --quiet --release --target thumbv7em-none-eabihf --bin bench)
elf="$root/targets/target/thumbv7em-none-eabihf/release/bench"
addr() { arm-none-eabi-nm "$elf" | awk -v s="$1" '$3 == s { print $1 }'; }
begin=$(addr bench_begin); end=$(addr bench_end)
[ -n "$begin" ] && [ -n "$end" ] || { echo "no bench_begin/bench_end in $elf" >&2; exit 1; }

log="$out/cortex-m4f"
timeout 600 qemu-system-arm -machine mps2-an386 -nographic \
  -semihosting-config enable=on,target=native -kernel "$elf" \
  -plugin "$plugin,start=0x$begin,stop=0x$end" > "$log.stdout" 2> "$log.stderr"

# The firmware built the host's scene.
cargo build --quiet --release -p raylane-bench --example count
host="$root/target/release/examples/count"
if ! diff <(grep '^scene' "$log.stdout") <("$host" digest); then
  echo "the firmware's scene differs from the host's" >&2
  exit 1
fi
# Window k belongs to the k-th cfg line.
paste -d' ' <(grep '^cfg' "$log.stdout") <(awk '$1 == "window" { print $3 }' "$log.stderr") \
  > "$out/cortex-m4f.txt"
cfgs=$(grep -c '^cfg' "$log.stdout"); wins=$(grep -c '^window' "$log.stderr")
[ "$cfgs" -eq "$wins" ] || { echo "$cfgs configurations but $wins windows" >&2; exit 1; }
"$host" table "$out/cortex-m4f.txt" \
  "Cortex-M4F (QEMU $(qemu-system-arm --version | awk 'NR==1 { print $4 }') mps2-an386, TCG plugin; scalar f32 lane, the M4F having no SIMD; opt-level s, LTO)" \
  | tee "$out/cortex-m4f.md"
