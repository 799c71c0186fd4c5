#!/usr/bin/env bash
# Write throughput of `mstar run --out` as CSV and as .npz on one model file:
# the same run without output, to .csv and to .npz, RUNS times each,
# alternating; prints each run's stepping wall time (the program's
# "wall time"), the file's size, and the extra time and MB/s of writing
# (against the median of the runs without output). Usage:
#   benches/output/throughput.sh BINARY MODEL_FILE T_END [RUNS] [COLUMNS]
# e.g. with `cargo xtask spatial-chain-file --links 100000 --out chain.toml`:
#   benches/output/throughput.sh target/release/mstar chain.toml 0.02 3
set -eu
bin=$1 model=$2 t_end=$3 runs=${4:-3} columns=${5:-}
export RAYON_NUM_THREADS=1
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
extra=()
[ -n "$columns" ] && extra=(--columns "$columns")
wall() { grep -oE 'wall time: [0-9.]+' | grep -oE '[0-9.]+'; }
declare -A times sizes
for _ in $(seq "$runs"); do
  times[none]+=" $("$bin" run "$model" --t-end "$t_end" 2>&1 | wall)"
  for ext in csv npz; do
    times[$ext]+=" $("$bin" run "$model" --t-end "$t_end" --out "$out/o.$ext" "${extra[@]}" 2>&1 | wall)"
    sizes[$ext]=$(stat -c %s "$out/o.$ext" 2>/dev/null || echo 0)
  done
done
median() { tr ' ' '\n' | grep . | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
base=$(echo "${times[none]}" | median)
echo "model: $model, t_end = $t_end s, ${runs} runs each${columns:+, --columns $columns}"
echo "no output: wall time (s):${times[none]} (median $base)"
for ext in csv npz; do
  m=$(echo "${times[$ext]}" | median)
  awk -v ext="$ext" -v t="${times[$ext]}" -v m="$m" -v b="$base" -v s="${sizes[$ext]}" 'BEGIN {
    d = m - b; printf "%s: wall time (s):%s (median %s); %.3f MB; writing %.2f s, %.0f MB/s\n",
      ext, t, m, s / 1e6, d, (d > 0 ? s / 1e6 / d : 0) }'
done
