#!/usr/bin/env bash
# The allocation trap works: an image whose main allocates (operator new) must stop with the
# board's allocation exit code (91) and say so, not run on.
# usage: firmware/traps_allocation.sh OUT_DIR
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=$1
FIRMWARE_EXTRA_FLAGS=-DFIRMWARE_ALLOCATE "$here/build.sh" m4 closed_form "$out" > /dev/null
status=0
timeout 60 qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none \
  -semihosting-config enable=on,target=native -icount shift=0 -kernel "$out/m4_closed_form.elf" \
  2> "$out/allocation.txt" || status=$?
cat "$out/allocation.txt"
[ "$status" -eq 91 ] && grep -q "ALLOCATION attempted" "$out/allocation.txt"
