#!/usr/bin/env bash
# Before/after of two packaged FMUs on a noisy machine: `bench-fmu --only` on each, configuration
# by configuration, in ROUNDS interleaved rounds (so that a slow spell of the machine hits both
# alike); compare the median of the rounds.
#
#   bash bench/interleaved.sh OLD.fmu NEW.fmu [ROUNDS]      (after cargo build --release)
#
# OLD_BENCH=path/to/old/bench-fmu runs the old FMU with the old build's own bench binary (whose
# configuration names set only variables that FMU knows); PAIRS lists "old name|new name" when
# the same configuration is named differently in the two builds (default: the names below, the
# same in both). Prints one table row per round, FMU ("old"/"new"), configuration and method.
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1
new=$2
rounds=${3:-3}
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
for round in $(seq "$rounds"); do
  for pair in "${pairs[@]}"; do
    for which in old new; do
      if [ "$which" = old ]; then
        fmu=$old bench=$old_bench config=${pair%%|*}
      else
        fmu=$new bench=./target/release/bench-fmu config=${pair##*|}
      fi
      [ -n "$config" ] || continue
      "$bench" --fmu "$fmu" --only "$config" --no-scipy --out /dev/null 2>&1 |
        grep '^| [A-Za-z]' | grep -v '^| configuration' | sed "s/^/$round $which /"
    done
  done
done
