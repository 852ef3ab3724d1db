#!/usr/bin/env bash
# Executed instructions per ray–primitive test of every raylane kernel on a microcontroller
# under QEMU, counted exactly by a TCG plugin. From scratch on Debian bookworm:
#
#   ./scripts/count-fw.sh [BOARD]     prints the Markdown table (also kept in target/count/BOARD.md)
#
# BOARD: cortex-m4f (default: mps2-an386, thumbv7em-none-eabihf), cortex-m3 (mps2-an385,
# thumbv7m-none-eabi, soft float), riscv32imafc or riscv32imac (qemu-system-riscv32 virt, hard
# and soft float). (./scripts/count-m4f.sh is the Cortex-M4F's.)
#
# 1. Installs QEMU, the binutils and the Rust target if missing.
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

board=${1:-cortex-m4f}
case "$board" in
  cortex-m4f) target=thumbv7em-none-eabihf; qemu=(qemu-system-arm -machine mps2-an386); pkg=qemu-system-arm
    nm=arm-none-eabi-nm; binutils=binutils-arm-none-eabi; name=Cortex-M4F; what="mps2-an386; scalar f32 lane, the M4F having no SIMD" ;;
  cortex-m3) target=thumbv7m-none-eabi; qemu=(qemu-system-arm -machine mps2-an385); pkg=qemu-system-arm
    nm=arm-none-eabi-nm; binutils=binutils-arm-none-eabi; name=Cortex-M3; what="mps2-an385; scalar f32 lane, soft float" ;;
  riscv32imafc|riscv32imac) target=$board-unknown-none-elf; pkg=qemu-system-misc
    qemu=(qemu-system-riscv32 -machine virt -bios none); nm=riscv64-unknown-elf-nm; binutils=binutils-riscv64-unknown-elf
    name="RISC-V rv32${board#riscv32}"; what="virt; scalar f32 lane, $([ "$board" = riscv32imafc ] && echo "hard float (F)" || echo "soft float")" ;;
  *) echo "usage: $0 [cortex-m4f|cortex-m3|riscv32imafc|riscv32imac]" >&2; exit 2 ;;
esac
need=()
command -v "${qemu[0]}" >/dev/null || need+=("$pkg")
command -v "$nm" >/dev/null || need+=("$binutils")
if [ ${#need[@]} -gt 0 ]; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
rustup target add "$target" 2>&1 | grep -v "is up to date" || true

plugin=$("$root/targets/plugin/build.sh")
(cd "$root/targets" && cargo build --quiet --release --target "$target" --bin bench)
elf="$root/targets/target/$target/release/bench"
addr() { "$nm" "$elf" | awk -v s="$1" '$3 == s { print $1 }'; }
begin=$(addr bench_begin); end=$(addr bench_end)
[ -n "$begin" ] && [ -n "$end" ] || { echo "no bench_begin/bench_end in $elf" >&2; exit 1; }

log="$out/$board"
timeout 600 "${qemu[@]}" -nographic \
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
  > "$out/$board.txt"
cfgs=$(grep -c '^cfg' "$log.stdout"); wins=$(grep -c '^window' "$log.stderr")
[ "$cfgs" -eq "$wins" ] || { echo "$cfgs configurations but $wins windows" >&2; exit 1; }
"$host" table "$out/$board.txt" \
  "$name (QEMU $("${qemu[0]}" --version | awk 'NR==1 { print $4 }') $what, TCG plugin; opt-level s, LTO)" \
  | tee "$out/$board.md"
