#!/usr/bin/env bash
# Times two mstar binaries on the same cases, alternating, one thread, and
# prints the µs per step of each run. Usage:
#   benches/ab/speed.sh BINARY_A BINARY_B [RUNS] [SPATIAL_CHAIN_FILE N_FOUR_BAR_FILE]
# The files come from `cargo xtask spatial-chain-file --links 10000 --out F`
# and `cargo xtask n-four-bar-file --bars 5000 --out F` (optional).
set -u
a=$1 b=$2 runs=${3:-3} chain=${4:-} nfb=${5:-}
export RAYON_NUM_THREADS=1
cases=(
  "chain --links 1000 --t-end 1"
  "chain --links 10000 --t-end 0.2"
  "chain --kind spatial-bars --links 1000 --t-end 0.5 --tol 1e-8 --rho 0.8"
)
out="$(mktemp -d)"
[ -n "$chain" ] && cases+=("run $chain --t-end 0.05 --out $out/o.csv")
[ -n "$nfb" ] && cases+=("run $nfb --t-end 0.02 --out $out/o.csv")
for c in "${cases[@]}"; do
  ta="" tb=""
  for _ in $(seq "$runs"); do
    # shellcheck disable=SC2086
    ta="$ta $("$a" $c 2>&1 | grep -oE 'time per step: [0-9.]+|\([0-9.]+ µs per step\)' | grep -oE '[0-9.]+' | head -1)"
    # shellcheck disable=SC2086
    tb="$tb $("$b" $c 2>&1 | grep -oE 'time per step: [0-9.]+|\([0-9.]+ µs per step\)' | grep -oE '[0-9.]+' | head -1)"
  done
  echo "$c"
  echo "  A:$ta"
  echo "  B:$tb"
done
rm -rf "$out"
