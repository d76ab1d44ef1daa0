#!/usr/bin/env bash
# Builds one firmware image, runs it in QEMU and checks it; the ctest of each (target, law).
# usage: firmware/run_image.sh TARGET LAW OUT_DIR HOST_REFERENCE_PROGRAM
# Fails on: a build or link error, a trap (fault or allocation), a failed law call, a deadline
# overrun, a run that does not end within 120 s, a measured stack above the static bound, or a
# trajectory outside its stated error against the host's double-precision run of the same loop.
# Writes OUT_DIR/TARGET_LAW.json with the footprint and cost figures.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
target=$1 law=$2 out=$3 reference=$4
name="${target}_${law}"
mkdir -p "$out"
rm -f "$out/$name.bin" "$out/$name.json"
"$here/build.sh" "$target" "$law" "$out" > /dev/null
case "$target" in
  m4) machine=mps2-an386 width=4 ;;
  m7) machine=mps2-an500 width=8 ;;
esac
n=2; case "$law" in arm* | differential_drive) n=3 ;; esac
# -icount shift=0: one instruction per virtual nanosecond, SysTick at 25 MHz (40 instructions a
# tick); the loop sleeps (WFI) between periods, so 10 s of loop take about 10 s.
status=0
timeout 120 qemu-system-arm -M "$machine" -nographic -monitor none -serial none \
  -semihosting-config enable=on,target=native -icount shift=0 -kernel "$out/$name.elf" \
  2> "$out/$name.txt" || status=$?
cat "$out/$name.txt"
case $status in
  0) ;;
  1) echo "FAIL: the law returned a failure status"; exit 1 ;;
  2) echo "FAIL: deadline overrun"; exit 1 ;;
  90) echo "FAIL: fault on the target"; exit 1 ;;
  91) echo "FAIL: allocation on the target"; exit 1 ;;
  124) echo "FAIL: QEMU did not finish within 120 s"; exit 1 ;;
  *) echo "FAIL: exit status $status"; exit 1 ;;
esac
# Worst-case stack of one control call from the call graph; newlib's math functions (sinf, cosf,
# expf and their argument reduction, whose __kernel_rem_pio2f keeps four 20-float arrays) are not
# in it and are allowed 512 bytes.
"$here/tools/stack_bound.py" "::control(" 512 "$out/$name".*.ci > "$out/$name.stack.txt"
cat "$out/$name.stack.txt"
bound=$(awk '/^static_bound/ { print $2 }' "$out/$name.stack.txt")
measured=$(awk '/^stack_bytes_measured/ { print $2 }' "$out/$name.txt")
[ "$measured" -le "$bound" ] || { echo "FAIL: stack measured $measured > static bound $bound"; exit 1; }
"$reference" "$law" "$out/$name.host.bin"
"$here/tools/compare.py" "$out/$name.bin" "$width" "$out/$name.host.bin" "$n" | tee "$out/$name.compare.txt"
read -r text data bss <<< "$(arm-none-eabi-size -A "$out/$name.elf" | awk '
  /^\.text|^\.ARM\.exidx|^\.init_array|^\.vectors/ { t += $2 } /^\.data/ { d += $2 } /^\.bss/ { b += $2 }
  END { print t, d, b }')"
value() {
  local v
  v=$(awk -v k="$1" '$1 == k { print $2 }' "$out/$name.txt" "$out/$name.compare.txt")
  [ -n "$v" ] || { echo "FAIL: the run did not report $1" >&2; exit 1; }
  echo "$v"
}
for key in law_state_bytes instructions_per_call_min instructions_per_call_mean instructions_per_call_max \
           max_tracking_error_nm q_max_difference qd_max_difference; do value "$key" > /dev/null; done
cat > "$out/$name.json" <<JSON
{"target": "$target", "law": "$law", "flash_bytes": $((text + data)), "ram_bytes": $((data + bss)),
 "law_state_bytes": $(value law_state_bytes), "stack_measured_bytes": $measured, "stack_bound_bytes": $bound,
 "instructions_per_call": {"min": $(value instructions_per_call_min), "mean": $(value instructions_per_call_mean), "max": $(value instructions_per_call_max)},
 "max_tracking_error_m": $(value max_tracking_error_nm)e-9,
 "q_max_difference": $(value q_max_difference), "qd_max_difference": $(value qd_max_difference)}
JSON
echo "firmware $name: ok"
