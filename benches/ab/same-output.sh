#!/usr/bin/env bash
# Runs every shipped model (models/*.toml, *.json, models/spatial/*.toml)
# with two mstar binaries and compares the CSV files byte for byte and the
# exit codes. Usage: benches/ab/same-output.sh BINARY_A BINARY_B
set -u
a=$1 b=$2
root="$(cd "$(dirname "$0")/../.." && pwd)"
out="$(mktemp -d)"
same=0 differ=0 exits=0
for f in "$root"/models/*.toml "$root"/models/*.json "$root"/models/spatial/*.toml; do
  n="${f#"$root"/models/}"; n="${n//\//_}"
  "$a" run "$f" --out "$out/a-$n.csv" >/dev/null 2>&1; ra=$?
  "$b" run "$f" --out "$out/b-$n.csv" >/dev/null 2>&1; rb=$?
  if [ "$ra" != "$rb" ]; then echo "exit codes differ: $n ($ra, $rb)"; exits=$((exits + 1)); continue; fi
  if cmp -s "$out/a-$n.csv" "$out/b-$n.csv"; then same=$((same + 1)); else echo "differs: $n"; differ=$((differ + 1)); fi
done
rm -rf "$out"
echo "same=$same differ=$differ exit-codes-differ=$exits"
[ "$differ" = 0 ] && [ "$exits" = 0 ]
