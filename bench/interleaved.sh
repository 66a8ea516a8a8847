#!/usr/bin/env bash
# Before/after of two packaged FMUs on a noisy machine: `bench-fmu --only` on each, configuration
# by configuration, in ROUNDS interleaved rounds (so that a slow spell of the machine hits both
# alike); compare the median of the rounds.
#
#   bash bench/interleaved.sh OLD.fmu NEW.fmu [ROUNDS]      (after cargo build --release)
#   ROUNDS=5 bash bench/interleaved.sh FMU                  (one FMU alone: its median and range)
#
# OLD_BENCH=path/to/old/bench-fmu runs the old FMU with the old build's own bench binary (whose
# configuration names set only variables that FMU knows); PAIRS lists "old name|new name" when
# the same configuration is named differently in the two builds (default: the names below, the
# same in both). Prints one table row per round, FMU ("old"/"new"), configuration and method,
# then a summary table: per FMU, configuration and method, the median real-time factor of the
# rounds and their range.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -eq 1 ]; then
  old="" new=$1 rounds=${ROUNDS:-5}
else
  old=$1 new=$2 rounds=${3:-3}
fi
old_bench=${OLD_BENCH:-./target/release/bench-fmu}
default_pairs=(
  "LOES motor alone (preset loes-motor)|LOES motor alone (preset loes-motor)"
  "LOES coupled 3x5|LOES coupled 3x5"
  "servo valve uncoupled|servo valve uncoupled"
  "servo valve coupled (defaults)|servo valve coupled (defaults)"
  "LOES coupled 20x20|LOES coupled 20x20"
)
if [ -n "${PAIRS:-}" ]; then
  mapfile -t pairs <<<"$PAIRS"
else
  pairs=("${default_pairs[@]}")
fi
rows=$(mktemp)
trap 'rm -f "$rows"' EXIT
for round in $(seq "$rounds"); do
  for pair in "${pairs[@]}"; do
    for which in old new; do
      if [ "$which" = old ]; then
        [ -n "$old" ] || continue
        fmu=$old bench=$old_bench config=${pair%%|*}
      else
        fmu=$new bench=./target/release/bench-fmu config=${pair##*|}
      fi
      [ -n "$config" ] || continue
      label=$which
      [ -n "$old" ] || label=fmu
      "$bench" --fmu "$fmu" --only "$config" --no-scipy --out /dev/null 2>&1 |
        grep '^| [A-Za-z]' | grep -v '^| configuration' | sed "s/^/$round $label /" |
        tee -a "$rows"
    done
  done
done
echo
echo "| FMU | configuration | method | real time (median) | range | rounds |"
echo "| --- | --- | --- | ---: | ---: | ---: |"
# Fields of a row: "ROUND WHICH | configuration | states | method | real time | ...".
awk -F'|' '{ split($1, rw, " "); key = rw[2] "|" $2 "|" $4; gsub(/ +$/, "", key)
             n[key]++; v[key, n[key]] = $5 + 0; if (!(key in order)) order[key] = ++keys; name[order[key]] = key }
     END { for (k = 1; k <= keys; k++) { key = name[k]; m = n[key]
             for (i = 1; i <= m; i++) a[i] = v[key, i]
             for (i = 2; i <= m; i++) { x = a[i]; j = i - 1; while (j > 0 && a[j] > x) { a[j + 1] = a[j]; j-- } a[j + 1] = x }
             med = (m % 2) ? a[(m + 1) / 2] : (a[m / 2] + a[m / 2 + 1]) / 2
             split(key, f, "|"); gsub(/^ +| +$/, "", f[2]); gsub(/^ +| +$/, "", f[3])
             printf "| %s | %s | %s | %.1f | %.1f-%.1f | %d |\n", f[1], f[2], f[3], med, a[1], a[m], m } }' "$rows"
