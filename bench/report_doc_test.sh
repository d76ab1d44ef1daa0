#!/bin/sh
# report_bench.py --doc on a copy of docs/performance.md, twice: the measured part is replaced by
# the report's tables, the hand-written part kept, and a second run gives the same page.
# usage: report_doc_test.sh PAGE REPORT_BENCH_PY BENCH_DIR WORK_DIR
set -eu
page=$1 report=$2 dir=$3 work=$4
mkdir -p "$work"
cp "$page" "$work/once.md"
/usr/bin/python3 "$report" "$dir" --doc "$work/once.md" > /dev/null
grep -q '^### Control law' "$work/once.md" || { echo "no control law table in the page"; exit 1; }
if [ -f "$dir/auth_bench.json" ]; then
  grep -q '^### Message authentication' "$work/once.md" || { echo "no authentication table in the page"; exit 1; }
fi
grep -q '^## Running them' "$work/once.md" || { echo "the hand-written part was lost"; exit 1; }
grep -q '^<!-- scripts/bench: end' "$work/once.md" || { echo "the end marker was lost"; exit 1; }
cp "$work/once.md" "$work/twice.md"
/usr/bin/python3 "$report" "$dir" --doc "$work/twice.md" > /dev/null
cmp "$work/once.md" "$work/twice.md" || { echo "a second run changed the page"; exit 1; }
cp "$page" "$work/broken.md"
sed -i '/scripts\/bench: end/d' "$work/broken.md"
if /usr/bin/python3 "$report" "$dir" --doc "$work/broken.md" > /dev/null 2>&1; then
  echo "a page without its end marker was accepted"; exit 1
fi
echo "report_doc_test: ok"
