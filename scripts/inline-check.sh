#!/usr/bin/env bash
# Checks that the per-level copies of raylane's queries (raylane::simd) run their hot paths
# with their level's features: in each x86-64 binary given, no function may call a
# `core::arch` intrinsic out of line except the cold paths listed below (f64 fallbacks, exact
# edge signs, tie breaks; each `#[inline(never)]`). A function the compiler leaves out of line
# inside a copy (a closure, an iterator adapter, `array::map`) is compiled for the baseline, so
# every intrinsic in it becomes a call: the same answers, several times slower.
#
#   ./scripts/inline-check.sh target/release/examples/render target/release/examples/game
set -euo pipefail
cold='^(raylane::hit::Closest<L>::wins_tie|raylane::hit::precise_unit|raylane::triangle::watertight::precise|raylane::sphere::precise|raylane::triangle::focal::exact_signs|std_detect::.*|libm::.*)$'
bad=0
for bin in "$@"; do
  found=$(objdump -d --no-show-raw-insn -C "$bin" | awk '
    /^[0-9a-f]+ <.*>:$/ { name = $0; sub(/^[0-9a-f]+ </, "", name); sub(/>:$/, "", name); next }
    /call.*<core::core_arch::/ { if (name !~ /^core::core_arch/) n[name]++ }
    END { for (f in n) printf "%s\t%d\n", f, n[f] }' | sort)
  hot=$(printf '%s\n' "$found" | awk -F'\t' -v cold="$cold" 'NF && $1 !~ cold { printf "  %5d calls in %s\n", $2, $1 }')
  if [ -n "$hot" ]; then
    echo "$bin: intrinsics called out of line (a hot path compiled without its level's features):"
    echo "$hot"
    bad=1
  else
    echo "$bin: every intrinsic inlined outside the cold paths"
  fi
done
exit $bad
