#!/usr/bin/env bash
# Builds one bare-metal image of the control law for an MPS2 board as QEMU models it.
# usage: firmware/build.sh TARGET LAW OUT_DIR
#   TARGET  m4 (Cortex-M4F, single-precision FPU, float; QEMU mps2-an386)
#           m7 (Cortex-M7, double-precision FPU, double; QEMU mps2-an500)
#   LAW     duffing | arm | closed_form | duffing_held | arm_held | cart_pole | arm_passive_wrist |
#           differential_drive
# Extra compiler flags may be passed in FIRMWARE_EXTRA_FLAGS (e.g. -DFIRMWARE_ALLOCATE).
# Writes OUT_DIR/TARGET_LAW.elf, its map, the -fstack-usage and -fcallgraph-info files.
# These are the flags a firmware project copies: C++20, no exceptions, no RTTI, no math errno,
# no thread-safe statics, newlib-nano, our own startup and linker script, no heap.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
target=$1 law=$2 out=$3
case "$target" in
  m4) cpu=(-mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard); scalar=float ;;
  m7) cpu=(-mcpu=cortex-m7 -mfpu=fpv5-d16 -mfloat-abi=hard); scalar=double ;;
  *) echo "unknown target $target (m4 or m7)" >&2; exit 2 ;;
esac
case "$law" in
  duffing) law_enum=kDuffing ;;
  arm) law_enum=kArm ;;
  closed_form) law_enum=kClosedForm ;;
  duffing_held) law_enum=kDuffingHeld ;;
  arm_held) law_enum=kArmHeld ;;
  cart_pole) law_enum=kCartPole ;;
  arm_passive_wrist) law_enum=kArmPassiveWrist ;;
  differential_drive) law_enum=kDifferentialDrive ;;
  *) echo "unknown law $law (duffing, arm, closed_form, duffing_held, arm_held, cart_pole, arm_passive_wrist, differential_drive)" >&2; exit 2 ;;
esac
mkdir -p "$out"
name="${target}_${law}"
objs=()
flags=("${cpu[@]}" -mthumb -O2 -std=c++20 -fno-exceptions -fno-rtti -fno-math-errno -fno-threadsafe-statics
       -fno-use-cxa-atexit -ffunction-sections -fdata-sections -fstack-usage -fcallgraph-info=su
       -DNDEBUG -DEIGEN_MAX_STATIC_ALIGN_BYTES=0 -DEIGEN_NO_IO
       "-DFIRMWARE_LAW=firmware::Law::$law_enum" "-DFIRMWARE_SCALAR=$scalar"
       "-DFIRMWARE_TRAJECTORY=\"$out/$name.bin\""
       -I"$root/controller/include" -isystem /usr/include/eigen3 -Wall -Wextra -Wno-psabi ${FIRMWARE_EXTRA_FLAGS:-})
for src in "$here/src/main.cpp" "$here/board/startup.cpp"; do
  obj="$out/$name.$(basename "$src" .cpp).o"
  (cd "$out" && arm-none-eabi-gcc "${flags[@]}" -dumpbase "$name.$(basename "$src" .cpp)" -c "$src" -o "$obj")
  objs+=("$obj")
done
arm-none-eabi-gcc "${cpu[@]}" -mthumb --specs=nano.specs -nostartfiles -T "$here/board/mps2.ld" \
  -Wl,--gc-sections -Wl,-Map="$out/$name.map" "${objs[@]}" -lm -o "$out/$name.elf"
echo "$out/$name.elf"
