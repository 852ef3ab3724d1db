#!/usr/bin/env bash
# Executed instructions per ray–primitive test of every raylane kernel on a Cortex-M4F (QEMU's
# mps2-an386): scripts/count-fw.sh for that board (see there; other boards: count-fw.sh BOARD).
exec "$(dirname "$0")/count-fw.sh" cortex-m4f "$@"
