#!/usr/bin/env bash
# Before/after of two packaged FMUs on a noisy machine: `bench-fmu --only` on each, configuration
# by configuration, in ROUNDS interleaved rounds (so that a slow spell of the machine hits both
# alike); compare the best of the rounds.
#
#   bash bench/interleaved.sh OLD.fmu NEW.fmu [ROUNDS]      (after cargo build --release)
#
# Prints one table row per round, FMU ("old"/"new"), configuration and method.
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1
new=$2
rounds=${3:-3}
configs=(
  "LOES motor alone (preset loes-motor)"
  "LOES coupled 3x5"
  "servo valve uncoupled"
  "servo valve coupled (defaults)"
  "LOES coupled 20x20"
)
for round in $(seq "$rounds"); do
  for config in "${configs[@]}"; do
    for which in old new; do
      fmu=$old
      [ "$which" = new ] && fmu=$new
      ./target/release/bench-fmu --fmu "$fmu" --only "$config" --no-scipy --out /dev/null 2>&1 |
        grep '^| [A-Za-z]' | grep -v '^| configuration' | sed "s/^/$round $which /"
    done
  done
done
