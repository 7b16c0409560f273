#!/usr/bin/env bash
# Runs every fuzz target for SECONDS (default 600) on one core each in turn, then merges
# what found new coverage into the kept corpus (fuzz/corpus/TARGET) and lists crashes
# (fuzz/artifacts/TARGET). Needs the nightly toolchain and cargo-fuzz
# (`cargo install cargo-fuzz`). Debug assertions are on (-a): an arithmetic overflow
# is a finding (the gcode crate wrapped G2147483649 to G1 silently without them). Usage: fuzz/run-all.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")"
secs=${1:-600}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(machine_toml urdf gcode measurement_csv tolerance_file tool_table linuxcnc_config batch_table)
dict_of() {
  case $1 in
    machine_toml|tolerance_file) echo dict/toml.dict ;;
    linuxcnc_config) echo dict/linuxcnc.dict ;;
    urdf) echo dict/urdf.dict ;;
    gcode) echo dict/gcode.dict ;;
    *) echo "" ;;
  esac
}
cargo +nightly fuzz build -O -a
for t in "${targets[@]}"; do
  mkdir -p "corpus-work/$t" "corpus/$t"
  d=$(dict_of "$t")
  extra=()
  [ -n "$d" ] && extra+=("-dict=$d")
  echo "== $t: ${secs}s"
  cargo +nightly fuzz run -O -a "$t" "corpus-work/$t" "corpus/$t" -- \
    -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -max_len=16384 \
    -print_final_stats=1 "${extra[@]}" 2>&1 | tail -25 || echo "== $t: stopped (see artifacts/$t)"
  # Keep only the inputs that add coverage to the kept corpus.
  cargo +nightly fuzz run -O -a "$t" "corpus/$t" "corpus-work/$t" -- -merge=1 2>&1 | grep "MERGE-OUTER: .* new files" || echo "== $t: merge failed"
done
ls -l artifacts/*/ 2>/dev/null || echo "no crashes kept"
