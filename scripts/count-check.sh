#!/usr/bin/env bash
# Recounts the instructions per test and checks them against their pins (scripts/test.sh runs
# this): x86-64-v3 under callgrind (scripts/count-x86.sh) and the Cortex-M4F under QEMU's TCG
# plugin (scripts/count-m4f.sh), both deterministic. Fails when a count rose more than 3 %
# above its pin in benches/counts/, or is missing.
#
#   ./scripts/count-check.sh          recount and check
#   ./scripts/count-check.sh --pin    recount and write the new pins (a deliberate change:
#                                     commit them with the reason in the message)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
pins="$root/benches/counts"
mkdir -p "$pins"
"$root/scripts/count-x86.sh" > /dev/null
"$root/scripts/count-m4f.sh" > /dev/null
host="$root/target/release/examples/count"   # built by count-m4f.sh for the table
status=0
for t in x86-64-v3 cortex-m4f; do
  if [ "${1:-}" = --pin ]; then
    cp "$root/target/count/$t.md" "$pins/$t.md"
    echo "pinned $pins/$t.md"
  else
    "$host" check "$pins/$t.md" "$root/target/count/$t.md" || status=1
  fi
done
exit "$status"
