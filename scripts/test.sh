#!/usr/bin/env bash
# Every test of raylane, host and QEMU alike, as CI runs it (.ci/run calls this script).
#
#   ./scripts/test.sh
#
# 1. Installs what it needs (Debian packages for QEMU and the cross linkers, rustup targets).
# 2. Formatting and clippy over the workspace.
# 3. The host test suite (x86-64 baseline), the checker over every vector file with every
#    method at every lane width, and the baseline digests of every method and width.
# 4. The host suite again built for x86-64-v3 (AVX2, FMA) and for the native CPU (AVX-512
#    here); their digests must equal the baseline.
# 5. The whole suite for aarch64-unknown-linux-gnu under qemu-aarch64 (wide's NEON path), and
#    its digests.
# 6. The firmware under targets/ on QEMU's mps2-an386 (Cortex-M4F) and mps2-an505 (Cortex-M33):
#    every vector through every method and width, and their digests.
# 7. Firmware checks: the kernels link with a panic handler that does not exist (no panic
#    path), their square roots are `vsqrt.f32`, and their flash size.
# 8. The demo's scene 4 rendered by the firmware on both boards (scalar lane, written to the
#    host through semihosting) equals the host's render at every packet width, byte for byte.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
start=$SECONDS
step() { printf '\n== %s  [%ss]\n' "$*" "$((SECONDS - start))"; }
fail() { printf '\nFAILED: %s\n' "$*" >&2; exit 1; }

step "system packages and rustup targets"
need=()
command -v qemu-system-arm >/dev/null || need+=(qemu-system-arm)
command -v qemu-aarch64 >/dev/null || need+=(qemu-user)
command -v aarch64-linux-gnu-gcc >/dev/null || need+=(gcc-aarch64-linux-gnu)
[ -e /usr/aarch64-linux-gnu/lib/crt1.o ] || need+=(libc6-dev-arm64-cross)
command -v arm-none-eabi-objdump >/dev/null || need+=(binutils-arm-none-eabi)
if [ ${#need[@]} -gt 0 ]; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "installing: ${need[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
rustup target add thumbv7em-none-eabihf thumbv8m.main-none-eabihf aarch64-unknown-linux-gnu 2>&1 | grep -v "is up to date" || true
rustup component add rustfmt clippy 2>&1 | grep -v "is up to date" || true

step "format and lints"
cargo fmt --all -- --check
(cd targets && cargo fmt -- --check)
cargo clippy --quiet --workspace --all-targets --features raylane/vectors,raylane/demo -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --quiet --no-deps --features vectors,demo

step "host test suite (x86-64)"
cargo test --quiet --features vectors,demo

step "checker: every method, every lane width"
cargo build --quiet --release --features vectors,demo --example check --example digest --example render
for method in $(./target/release/examples/check --list); do
  for lanes in 1 4 8 16; do
    printf '%-16s x%-3s' "$method" "$lanes"
    ./target/release/examples/check --method "$method" --lanes "$lanes" tests/vectors/*.txt | tail -n 1
  done
done
printf '%-20s' "recommended"
./target/release/examples/check tests/vectors/*.txt | tail -n 1

mkdir -p target/digests
./target/release/examples/digest | grep '^digest' > target/digests/x86-64.txt
same() { # same NAME FILE: FILE's digests equal the baseline's
  if diff -q "$root/target/digests/x86-64.txt" "$2" >/dev/null; then
    echo "$1: $(wc -l < "$2") digests equal to x86-64"
  else
    diff "$root/target/digests/x86-64.txt" "$2" || true
    fail "$1 digests differ from x86-64"
  fi
}

for cpu in x86-64-v3 native; do
  step "host test suite, -C target-cpu=$cpu"
  RUSTFLAGS="-C target-cpu=$cpu" cargo test --quiet --features vectors,demo --target-dir "target/cpu-$cpu"
  RUSTFLAGS="-C target-cpu=$cpu" cargo run --quiet --release --features vectors,demo --example digest \
    --target-dir "target/cpu-$cpu" | grep '^digest' > "target/digests/$cpu.txt"
  same "$cpu" "target/digests/$cpu.txt"
done

step "AArch64 (NEON) test suite under qemu-aarch64"
cargo test --quiet --release --features vectors,demo --target aarch64-unknown-linux-gnu
cargo run --quiet --release --features vectors,demo --example digest --target aarch64-unknown-linux-gnu \
  | grep '^digest' > target/digests/aarch64.txt
same aarch64 target/digests/aarch64.txt

step "firmware on QEMU: Cortex-M4F (mps2-an386) and Cortex-M33 (mps2-an505)"
cd "$root/targets"
for t in thumbv7em-none-eabihf thumbv8m.main-none-eabihf; do
  cargo build --quiet --release --target "$t" --bins
done
for t in thumbv7em-none-eabihf:cortex-m4f thumbv8m.main-none-eabihf:cortex-m33; do
  target=${t%%:*}; name=${t##*:}
  log="$root/target/digests/$name.log"
  status=0
  cargo run --quiet --release --target "$target" --bin vectors > "$log" 2>&1 || status=$?
  grep -v '^digest' "$log" | grep -E 'FAILED|differs|cannot' || true
  tail -n 1 "$log" | sed "s/^/$name: /"
  [ "$status" -eq 0 ] || fail "$name firmware exited with $status (see $log)"
  grep -qE '^[0-9]+ passed, 0 failed$' "$log" || fail "$name firmware printed no result (see $log)"
  grep '^digest' "$log" > "$root/target/digests/$name.txt"
  same "$name" "$root/target/digests/$name.txt"
done

step "firmware checks: no panic path, hardware square root, flash size"
m4="target/thumbv7em-none-eabihf/release"
m33="target/thumbv8m.main-none-eabihf/release"
# The `kernels` (f32) and `kernels_x4` (f32 and f32x4) binaries' panic handler calls a symbol
# defined nowhere: they linked, so no kernel can reach a panic.
echo "no panic path: kernels and kernels_x4 linked for both boards with an undefined panic handler"
for bin in "$m4/kernels" "$m33/kernels"; do
  n=$(arm-none-eabi-objdump -d "$bin" | grep -c 'vsqrt\.f32' || true)
  [ "$n" -gt 0 ] || fail "no vsqrt.f32 in $bin"
  if arm-none-eabi-nm -C "$bin" | grep -qiE 'sqrtf'; then fail "a software f32 square root is linked in $bin"; fi
  echo "hardware square root: $n vsqrt.f32 in $bin, no software sqrtf"
done
text() { arm-none-eabi-size -A -d "$1" | awk '$1==".text"{print $2}'; }
empty=$(text "$m4/empty")
echo "flash on Cortex-M4F: every kernel, scalar: $(( $(text "$m4/kernels") - empty )) B of code;" \
  "with 4-lane packets too: $(( $(text "$m4/kernels_x4") - empty )) B (empty firmware: $empty B)"
cd "$root"

step "firmware render vs host render: scene 4 at 64x48, byte for byte"
mkdir -p target/render
cd "$root/targets"
for t in thumbv7em-none-eabihf:cortex-m4f thumbv8m.main-none-eabihf:cortex-m33; do
  target=${t%%:*}; name=${t##*:}
  log="$root/target/render/$name.log"
  rm -f target/render.ppm "$root/target/render/$name.ppm"
  status=0
  cargo run --quiet --release --target "$target" --bin render > "$log" 2>&1 || status=$?
  sed "s/^/$name: /" "$log"
  [ "$status" -eq 0 ] || fail "$name render firmware exited with $status (see $log)"
  [ -s target/render.ppm ] || fail "$name render firmware wrote no image (see $log)"
  mv target/render.ppm "$root/target/render/$name.ppm"
done
cd "$root"
for lanes in 1 4 8 16; do
  ./target/release/examples/render --scene mix --size 64x48 --lanes "$lanes" \
    --ppm "target/render/host-x$lanes.ppm" | sed 's/^/host: /'
  for name in cortex-m4f cortex-m33; do
    cmp "target/render/host-x$lanes.ppm" "target/render/$name.ppm" \
      || fail "$name render differs from the host's at $lanes lanes"
  done
done
echo "firmware images equal to the host's at 1, 4, 8 and 16 lanes ($(wc -c < target/render/cortex-m4f.ppm) bytes)"

step "digests"
for f in target/digests/*.txt; do printf '%-12s %s\n' "$(basename "$f" .txt)" "$(md5sum < "$f" | cut -c1-16)"; done
printf '\nall tests passed in %ss\n' "$((SECONDS - start))"
