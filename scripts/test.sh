#!/usr/bin/env bash
# Every test of raylane, host and QEMU alike, as CI runs it (.ci/run calls this script).
#
#   ./scripts/test.sh
#
# 1. Installs what it needs, idempotently: Debian packages (QEMU for Arm and RISC-V, the
#    AArch64 cross linker, Arm and RISC-V binutils, Embree for the peer benchmarks, valgrind), rustup
#    targets, and the MSRV toolchain (Cargo.toml's rust-version) with the minimal profile.
# 2. Formatting, clippy over the workspace and over the benchmarks with their peers, rustdoc.
# 3. The library builds for the host, AArch64, thumbv6m (Cortex-M0), thumbv7m (Cortex-M3),
#    thumbv7em (M4F), thumbv8m.main (M33), riscv32imac and riscv32imafc, with no default
#    features and with each feature.
# 4. MSRV: the library built and its test suite run with the rust-version toolchain.
# 5. The host test suite (a default x86-64 build) at every SIMD level of the CPU, chosen at run
#    time (raylane::simd; RAYLANE_SIMD forces the lower ones), the checker over every vector
#    file with every method at every lane width, and the digests of every method and width at
#    every level.
#    Every level's copy checked for intrinsics left out of line (scripts/inline-check.sh).
# 6. The host suite again built for x86-64-v3 (AVX2, FMA) and for the native CPU (AVX-512
#    here); their digests must equal the baseline.
# 7. Instructions per ray–primitive test of every kernel through the library's query, on
#    x86-64-v3 (callgrind) and the Cortex-M4F (QEMU plugin), against their pins in
#    benches/counts/ (scripts/count-check.sh): no count may rise more than 3 %.
# 8. The whole suite for aarch64-unknown-linux-gnu under qemu-aarch64 (wide's NEON path), and
#    its digests.
# 9. The firmware under targets/ on six QEMU boards: micro:bit (Cortex-M0; every vector at
#    lane width 1, the flash holding no more), mps2-an385 (Cortex-M3, soft float), mps2-an386
#    (Cortex-M4F), mps2-an505 (Cortex-M33), and RISC-V 32 `virt` soft float (rv32imac) and
#    hard float (rv32imafc): every vector through every method and width, digests equal to
#    x86-64's, and the op-count report measured on the target equal to the host's.
# 10. Firmware checks: the kernels link with a panic handler that does not exist (no panic
#    path) on every target; square roots are `vsqrt.f32` (M4F, M33) and `fsqrt.s`
#    (rv32imafc) with no software sqrtf; code size per target (scalar kernels, and with
#    4-lane packets).
# 11. The demo's scene 4 rendered by the firmware on five boards (scalar lane, written to the
#    host through semihosting) equals the host's render at every packet width, byte for byte;
#    the vendored bunny baked on the host (targets/build.rs) and traced from flash on all six
#    boards, the Cortex-M0 included, equals the host's render at every width the board holds,
#    with a table of each board's flash, RAM (stack painting) and largest mesh that fits.
# 12. The README's firmware crate (examples/firmware) built and run on the Cortex-M4F and M0.
# 13. A summary: every configuration with its digest, code size and run time.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
start=$SECONDS
step() { printf '\n== %s  [%ss]\n' "$*" "$((SECONDS - start))"; }
fail() { printf '\nFAILED: %s\n' "$*" >&2; exit 1; }

step "system packages, rustup targets, MSRV toolchain"
need=()
command -v qemu-system-arm >/dev/null || need+=(qemu-system-arm)
command -v qemu-system-riscv32 >/dev/null || need+=(qemu-system-misc)
command -v qemu-aarch64 >/dev/null || need+=(qemu-user)
command -v aarch64-linux-gnu-gcc >/dev/null || need+=(gcc-aarch64-linux-gnu)
[ -e /usr/aarch64-linux-gnu/lib/crt1.o ] || need+=(libc6-dev-arm64-cross)
command -v arm-none-eabi-objdump >/dev/null || need+=(binutils-arm-none-eabi)
command -v riscv64-unknown-elf-objdump >/dev/null || need+=(binutils-riscv64-unknown-elf)
[ -e /usr/include/embree3/rtcore.h ] || need+=(libembree-dev)
command -v valgrind >/dev/null || need+=(valgrind)
if [ ${#need[@]} -gt 0 ]; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "installing: ${need[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
embedded=(thumbv6m-none-eabi thumbv7m-none-eabi thumbv7em-none-eabihf thumbv8m.main-none-eabihf
  riscv32imac-unknown-none-elf riscv32imafc-unknown-none-elf)
rustup target add "${embedded[@]}" aarch64-unknown-linux-gnu 2>&1 | grep -v "is up to date" || true
rustup component add rustfmt clippy 2>&1 | grep -v "is up to date" || true
msrv=$(awk -F'"' '/^rust-version/ { print $2; exit }' Cargo.toml)
rustup toolchain list | grep -q "^$msrv-" \
  || rustup toolchain install "$msrv" --profile minimal --no-self-update 2>&1 | tail -n 1

step "format and lints"
cargo fmt --all -- --check
(cd targets && cargo fmt -- --check)
cargo clippy --quiet --workspace --all-targets -- -D warnings
# The benchmarks against the peers (Embree, obvhs, parry3d, bevy) compile and pass clippy too.
cargo clippy --quiet -p raylane-bench --features peers --all-targets -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --quiet --no-deps -p raylane -p raylane-lab

step "library builds: host, AArch64 and every embedded target; the lab beside it"
for t in x86_64-unknown-linux-gnu aarch64-unknown-linux-gnu "${embedded[@]}"; do
  features=("" alloc)
  case "$t" in *linux*) features+=(std) ;; esac
  for f in "${features[@]}"; do
    cargo build --quiet --lib --target "$t" --no-default-features ${f:+--features "$f"} \
      --target-dir target/matrix || fail "the library does not build for $t with features [$f]"
  done
  cargo build --quiet --lib --target "$t" -p raylane-lab --target-dir target/matrix \
    || fail "the lab does not build for $t"
  echo "$t: the library (no default features, ${features[*]:1}) and the lab build"
done

step "MSRV: the library built and tested with Rust $msrv"
for f in "" alloc std; do
  cargo "+$msrv" build --quiet --lib --no-default-features ${f:+--features "$f"} --target-dir target/msrv
done
# The library's own tests and doctests, and the programs a user would write (the render, the
# game's frame), at the MSRV. The suite (tests/suite, one binary that instantiates every query
# at every width and SIMD level) runs on stable, below: Rust 1.89 runs out of memory (over
# 20 GB) compiling it.
{ cargo "+$msrv" test --quiet -p raylane --target-dir target/msrv --lib \
    && cargo "+$msrv" test --quiet -p raylane --target-dir target/msrv --doc \
    && cargo "+$msrv" build --quiet --release -p raylane --target-dir target/msrv \
      --example render --example game; } \
  > target/msrv.log 2>&1 || { cat target/msrv.log; fail "the tests fail with Rust $msrv"; }
grep -E '^test result' target/msrv.log | sed "s/^/rust $msrv: /"
echo "rust $msrv ($(rustc "+$msrv" --version)): the library builds with every feature, its unit and doc tests pass, the render and game examples build"

step "host test suite (x86-64, a default build: every SIMD level this CPU has, chosen at run time)"
# The SIMD levels of this CPU (raylane::simd): the suite runs once at the best (detected) and
# again at each lower one (RAYLANE_SIMD), the same binary.
flags=$(grep -m1 '^flags' /proc/cpuinfo || true)
has() { for f in "$@"; do [[ " $flags " == *" $f "* ]] || return 1; done; }
levels=(baseline)
has avx2 fma bmi1 bmi2 movbe f16c && levels+=(avx2)
has avx2 fma bmi1 bmi2 movbe f16c avx512f avx512bw avx512cd avx512dq avx512vl && levels+=(avx512)
echo "SIMD levels of this CPU: ${levels[*]}"
# In release: a debug build of the suite (every query copied per SIMD level, each copy
# inlined whole) needs more than 20 GB to compile; the release build a fraction of that.
cargo test --quiet --release
for lv in "${levels[@]:0:${#levels[@]}-1}"; do
  echo "suite at RAYLANE_SIMD=$lv"
  RAYLANE_SIMD=$lv cargo test --quiet --release --test suite 2>&1 | grep -E '^test result|FAILED|panicked' \
    || fail "the suite fails at SIMD level $lv"
done

step "checker: every method, every lane width"
cargo build --quiet --release --example check --example digest --example render
for method in $(./target/release/examples/check --list); do
  for lanes in 1 4 8 16; do
    printf '%-16s x%-3s' "$method" "$lanes"
    ./target/release/examples/check --method "$method" --lanes "$lanes" tests/vectors/*.txt | tail -n 1
  done
done
printf '%-20s' "recommended"
./target/release/examples/check tests/vectors/*.txt | tail -n 1

step "every SIMD level's copy inlined: no intrinsic called out of line on a hot path"
# A function the compiler leaves out of line inside a level's copy runs without its level's
# instructions (scripts/inline-check.sh): checked on the render, on the scenes benchmark
# (every set, kernel and query kind it times), on the per-test counts (every kernel on its
# library path at every width) and on the game (an owned scene's queries, packets and
# filters), as users build them.
cargo build --quiet --release -p raylane-bench --features peers --example scenes --example count
cargo build --quiet --release --example game
./scripts/inline-check.sh target/release/examples/render target/release/examples/scenes \
  target/release/examples/count target/release/examples/game \
  || fail "a hot path runs without its SIMD level's instructions"

mkdir -p target/digests
# Run times of the digest runs: "NAME SECONDS" lines.
: > target/digests/times
timed() { # timed NAME CMD...: runs CMD, records its wall time under NAME, returns its status
  local t0 t1 rc=0
  t0=$(date +%s.%N)
  "${@:2}" || rc=$?
  t1=$(date +%s.%N)
  awk -v n="$1" -v a="$t0" -v b="$t1" 'BEGIN { print n, b - a }' >> "$root/target/digests/times"
  return "$rc"
}
timed x86-64 ./target/release/examples/digest > target/digests/x86-64.log
grep '^digest' target/digests/x86-64.log > target/digests/x86-64.txt
# The Cortex-M0 embeds the subset of files in targets/m0-vectors.txt: the host's digests over it.
rm -rf target/vectors-m0 && mkdir -p target/vectors-m0
grep -v '^#' targets/m0-vectors.txt | while read -r f; do [ -z "$f" ] || cp "tests/vectors/$f.txt" target/vectors-m0/; done
./target/release/examples/digest target/vectors-m0 | grep '^digest' > target/digests/x86-64-m0.txt
same() { # same NAME FILE [BASE]: FILE's digests equal BASE's (default: x86-64's), for the widths it has
  local want
  want=$(grep -F -f <(awk '{ print " " $3 " " }' "$2" | sort -u) "${3:-$root/target/digests/x86-64.txt}")
  if [ "$(wc -l < "$2")" -gt 0 ] && diff -q <(echo "$want") "$2" >/dev/null; then
    echo "$1: $(wc -l < "$2") digests equal to x86-64"
  else
    diff <(echo "$want") "$2" || true
    fail "$1 digests differ from x86-64"
  fi
}

# The default build's digests at each lower SIMD level (the run above is at the best one).
for lv in "${levels[@]:0:${#levels[@]}-1}"; do
  RAYLANE_SIMD=$lv ./target/release/examples/digest | grep '^digest' > "target/digests/x86-64-$lv.txt"
  same "x86-64 at SIMD level $lv" "target/digests/x86-64-$lv.txt"
done

# Builds for a CPU (what a user who sets target-cpu gets: `wide`'s vectors at that level, no
# run-time copies): their digests. (The suite ran above at every level of the default build;
# it no longer runs again per target-cpu build, whose compile doubled the run.)
for cpu in x86-64-v3 native; do
  step "digests, -C target-cpu=$cpu"
  RUSTFLAGS="-C target-cpu=$cpu" cargo build --quiet --release --example digest \
    --target-dir "target/cpu-$cpu"
  timed "$cpu" "target/cpu-$cpu/release/examples/digest" > "target/digests/$cpu.log"
  grep '^digest' "target/digests/$cpu.log" > "target/digests/$cpu.txt"
  same "$cpu" "target/digests/$cpu.txt"
done

step "instructions per test, recounted against their pins (benches/counts/)"
# callgrind on x86-64-v3 and QEMU's TCG plugin on the Cortex-M4F, both exact and repeatable:
# a count more than 3 % above its pin fails (a deliberate change re-pins: count-check.sh --pin).
./scripts/count-check.sh

step "AArch64 (NEON) test suite under qemu-aarch64"
cargo test --quiet --release --target aarch64-unknown-linux-gnu
cargo build --quiet --release --example digest --target aarch64-unknown-linux-gnu
timed aarch64 qemu-aarch64 -L /usr/aarch64-linux-gnu \
  target/aarch64-unknown-linux-gnu/release/examples/digest > target/digests/aarch64.log
grep '^digest' target/digests/aarch64.log > target/digests/aarch64.txt
same aarch64 target/digests/aarch64.txt

# NAME:TARGET:BOARD of every firmware configuration.
boards=(cortex-m0:thumbv6m-none-eabi:microbit cortex-m3:thumbv7m-none-eabi:mps2-an385
  cortex-m4f:thumbv7em-none-eabihf:mps2-an386 cortex-m33:thumbv8m.main-none-eabihf:mps2-an505
  rv32imac:riscv32imac-unknown-none-elf:virt rv32imafc:riscv32imafc-unknown-none-elf:virt)

step "firmware on QEMU: Cortex-M0, M3, M4F, M33, RISC-V rv32imac and rv32imafc"
cargo run --quiet --example opcount -- --csv | tail -n +2 > target/digests/opcount.csv
cd "$root/targets"
# One target at a time: cargo unifies the features of target-specific dependencies across the
# targets of one invocation (cortex-m's and riscv's critical-section features clash).
for t in "${embedded[@]}"; do
  cargo build --quiet --release --target "$t" --bins
done
for b in "${boards[@]}"; do
  IFS=: read -r name target board <<< "$b"
  log="$root/target/digests/$name.log"
  status=0
  timed "$name" cargo run --quiet --release --target "$target" --bin vectors > "$log" 2>&1 || status=$?
  grep -v '^digest' "$log" | grep -E 'FAILED|differs|cannot|panicked' || true
  grep '^vectors stack' "$log" | sed "s/^/$name ($board): /" || true
  tail -n 1 "$log" | sed "s/^/$name ($board): /"
  [ "$status" -eq 0 ] || fail "$name firmware exited with $status (see $log)"
  grep -qE '^[0-9]+ passed, 0 failed$' "$log" || fail "$name firmware printed no result (see $log)"
  grep '^digest' "$log" > "$root/target/digests/$name.txt"
  base="$root/target/digests/x86-64.txt"; [ "$name" != cortex-m0 ] || base="$root/target/digests/x86-64-m0.txt"
  same "$name" "$root/target/digests/$name.txt" "$base"
  diff <(sed -n 's/^opcount //p' "$log") "$root/target/digests/opcount.csv" \
    || fail "$name: the op counts measured on the target differ from the host's"
  echo "$name: op-count report measured on the target equal to the host's ($(wc -l < "$root/target/digests/opcount.csv") rows)"
done

step "firmware checks: no panic path, hardware square root, code size"
# The `kernels` (f32) and `kernels_x4` (f32 and f32x4) binaries' panic handler calls a symbol
# defined nowhere: they linked, so no kernel can reach a panic.
echo "no panic path: kernels and kernels_x4 linked for all six targets with an undefined panic handler"
tools() { case "$1" in riscv*) echo riscv64-unknown-elf ;; *) echo arm-none-eabi ;; esac; }
for t in thumbv7em-none-eabihf:vsqrt.f32 thumbv8m.main-none-eabihf:vsqrt.f32 riscv32imafc-unknown-none-elf:fsqrt.s; do
  target=${t%%:*}; insn=${t##*:}; bin="target/$target/release/kernels"; tp=$(tools "$target")
  n=$("$tp-objdump" -d "$bin" | grep -c "	${insn//./\\.}" || true)
  [ "$n" -gt 0 ] || fail "no $insn in $bin"
  # (grep -c, not grep -q: under pipefail, nm killed by an early exit of grep would fail the pipe)
  [ "$("$tp-nm" -C "$bin" | grep -ciE 'sqrtf' || true)" -eq 0 ] \
    || fail "a software f32 square root is linked in $bin"
  echo "hardware square root: $n $insn in $bin, no software sqrtf"
done
for target in thumbv6m-none-eabi thumbv7m-none-eabi riscv32imac-unknown-none-elf; do
  [ "$("$(tools "$target")-nm" -C "target/$target/release/kernels" | grep -c 'libm::math::sqrt::sqrtf' || true)" -gt 0 ] \
    || fail "no libm sqrtf in $target's kernels"
done
echo "software square root (libm's correctly rounded sqrtf) on the cores without one: Cortex-M0, M3, rv32imac"
text() { "$(tools "$2")-size" -A -d "target/$2/release/$1" | awk '$1==".text"{print $2}'; }
: > "$root/target/digests/sizes"
{
  echo "| target | core (QEMU board) | scalar kernels | with 4-lane packets | empty firmware |"
  echo "| --- | --- | ---: | ---: | ---: |"
  for b in "${boards[@]}"; do
    IFS=: read -r name target board <<< "$b"
    empty=$(text empty "$target")
    k1=$(( $(text kernels "$target") - empty )); k4=$(( $(text kernels_x4 "$target") - empty ))
    echo "| \`$target\` | $name ($board) | $k1 B | $k4 B | $empty B |"
    echo "$name $k1 $k4" >> "$root/target/digests/sizes"
  done
} > "$root/target/digests/size.md"
echo "code size (.text of every kernel, minus the empty firmware's; opt-level s, LTO):"
cat "$root/target/digests/size.md"
cd "$root"

step "firmware render vs host render: scene 4 at 64x48, byte for byte"
mkdir -p target/render
cd "$root/targets"
renders=()
for b in "${boards[@]}"; do
  IFS=: read -r name target board <<< "$b"
  # The Cortex-M0's 16 KB of RAM cannot hold the 9 KB image beside the scene.
  [ "$name" != cortex-m0 ] || continue
  renders+=("$name")
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
  for name in "${renders[@]}"; do
    cmp "target/render/host-x$lanes.ppm" "target/render/$name.ppm" \
      || fail "$name render differs from the host's at $lanes lanes"
  done
done
echo "firmware images (${renders[*]}) equal to the host's at 1, 4, 8 and 16 lanes ($(wc -c < target/render/cortex-m4f.ppm) bytes)"

step "firmware BVH from flash vs host: the bunny baked on the host, traced on all six boards, byte for byte"
# targets/build.rs bakes the vendored bunny (raylane::bvh::bake) into the `bvh` binary's flash;
# targets/src/bin/bvh.rs opens it in place (Baked::open checks it, copies nothing), renders
# 64x48 primary rays at 1 lane (and at 4, 8 and 16 lanes, checking they agree, on every board
# but the Cortex-M0, whose flash holds the scalar path only) and writes the image; the host
# renders the same picture with the same code (raylane_lab::demo::bunny) at each width.
mkdir -p target/bvh
cd "$root/targets"
bvhs=()
: > "$root/target/bvh/memory.md"
{
  echo "| target | core (QEMU board) | flash: code + tree + rest = used of linked size | RAM: .data+.bss; one query's stack; the program's peak; of linked size | largest mesh in the free flash |"
  echo "| --- | --- | --- | --- | ---: |"
} >> "$root/target/bvh/memory.md"
for b in "${boards[@]}"; do
  IFS=: read -r name target board <<< "$b"
  bvhs+=("$name")
  log="$root/target/bvh/$name.log"
  rm -f target/bvh.ppm "$root/target/bvh/$name.ppm"
  status=0
  cargo run --quiet --release --target "$target" --bin bvh > "$log" 2>&1 || status=$?
  sed "s/^/$name: /" "$log"
  [ "$status" -eq 0 ] || fail "$name bvh firmware exited with $status (see $log)"
  [ -s target/bvh.ppm ] || fail "$name bvh firmware wrote no image (see $log)"
  mv target/bvh.ppm "$root/target/bvh/$name.ppm"
  elf="target/$target/release/bvh"
  read -r text rodata data bss < <("$(tools "$target")-size" -A -d "$elf" \
    | awk '$1==".text"{t=$2} $1==".rodata"{r=$2} $1==".data"{d=$2} $1==".bss"{b=$2} END{print t+0, r+0, d+0, b+0}')
  tree=$(sed -n 's/^bvh bunny: baked .*: \([0-9]*\) B in flash.*/\1/p' "$log")
  tris=$(sed -n 's/^bvh bunny: baked \([0-9]*\) triangles.*/\1/p' "$log")
  query=$(sed -n 's/^bvh stack: one query \([0-9]*\) B.*/\1/p' "$log")
  peak=$(sed -n 's/^bvh stack: .*the whole program \([0-9]*\) B.*/\1/p' "$log")
  [ -n "$tree" ] && [ -n "$query" ] || fail "$name bvh firmware printed no sizes (see $log)"
  # The board's flash, from the memory.x that targets/build.rs links for the target.
  case "$board" in virt) mem=memory/riscv-virt.x ;; *) mem=memory/$board.x ;; esac
  kb() { awk -v r="$1" '$1 == r { v = $NF; print (v ~ /M/ ? v * 1024 : v + 0) }' "$mem"; }
  size_k=$(kb FLASH); ram_k=$(kb RAM)
  flash=$((size_k * 1024)); used=$((text + rodata + data))
  # Free flash over the bunny's bytes per triangle: the largest mesh of its kind that would fit.
  fits=$(( (flash - used + tree) * tris / tree ))
  echo "| \`$target\` | $name ($board) | $text + $tree + $((rodata + data - tree)) = $used B of $size_k KB | $((data + bss)) B; $query B; $peak B; of $ram_k KB | $fits triangles |" >> "$root/target/bvh/memory.md"
done
cd "$root"
for lanes in 1 4 8 16; do
  ./target/release/examples/render --scene bunny-fw --size 64x48 --lanes "$lanes" \
    --ppm "target/bvh/host-x$lanes.ppm" | sed 's/^/host: /'
  for name in "${bvhs[@]}"; do
    cmp "target/bvh/host-x$lanes.ppm" "target/bvh/$name.ppm" \
      || fail "$name bvh render differs from the host's at $lanes lanes"
  done
done
echo "firmware BVH images (${bvhs[*]}) equal to the host's at 1, 4, 8 and 16 lanes"
echo "the baked bunny on each board (flash and RAM as linked and as measured by stack painting):"
cat target/bvh/memory.md

step "examples/firmware: the README's firmware crate, built and run on the Cortex-M4F and M0"
# A crate to copy (its own workspace): build.rs bakes mesh.obj (raylane::bvh::bake), src/main.rs
# links it with include_baked!, opens it with Baked::open and prints the closest hit through
# semihosting. README.md quotes it (tests/suite/docs/readme_firmware.rs keeps the quotes true)
# and says what it prints.
cd "$root/examples/firmware"
cargo fmt -- --check || fail "examples/firmware is not formatted"
for t in thumbv7em-none-eabihf thumbv6m-none-eabi; do
  cargo build --quiet --release --target "$t" || fail "examples/firmware does not build for $t"
  status=0
  out=$(timeout 120 cargo run --quiet --release --target "$t" 2>&1) || status=$?
  [ "$status" -eq 0 ] || fail "examples/firmware exited with $status on $t: $out"
  grep -qF "\`$out\`" "$root/README.md" || fail "examples/firmware printed '$out' on $t, not what README.md says"
  text=$("$(tools "$t")-size" -A -d "target/$t/release/raylane-firmware-example" | awk '$1==".text"{print $2}')
  echo "examples/firmware $t: $out (.text $text B)"
done
cd "$root"

step "summary: every configuration, its digest, code size and digest run time"
# The digest: the first 16 hex digits of the MD5 of the configuration's digest lines (the
# Cortex-M0 has the x1 lines only: compare it with x86-64 x1).
h() { md5sum < "$1" | cut -c1-16; }
grep ' x1 ' target/digests/x86-64.txt > target/digests/x86-64-x1.txt
printf '%-11s %-30s %-17s %-17s %-22s %s\n' config target "digest (all)" "digest (x1)" "code: x1 / x4 (B)" "run (s)"
for c in "x86-64:x86_64 (baseline)" "x86-64-v3:x86_64 cpu=x86-64-v3" "native:x86_64 cpu=native" \
         "aarch64:aarch64 (qemu-aarch64)" \
         "${boards[@]}"; do
  IFS=: read -r name target _ <<< "$c"
  f=target/digests/$name.txt
  all=$(h "$f"); [ "$name" != cortex-m0 ] || all="(x1, subset)"
  x1=$(grep ' x1 ' "$f" | md5sum | cut -c1-16)
  size=$(awk -v n="$name" '$1 == n { print $2 " / " $3 }' target/digests/sizes 2>/dev/null)
  run=$(awk -v n="$name" '$1 == n { printf "%.2f", $2 }' target/digests/times)
  printf '%-11s %-30s %-17s %-17s %-22s %s\n' "$name" "$target" "$all" "$x1" "${size:--}" "$run"
done
printf '\nall tests passed in %ss\n' "$((SECONDS - start))"
