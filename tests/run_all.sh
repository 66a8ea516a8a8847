#!/usr/bin/env bash
# The project's test command: installs what is missing (tests/setup.sh), builds the FMU, then runs
# the Rust tests (cargo test) and the import-side Python tests (pytest, with fmpy, libcosim and
# fmutool). Fails if either fails; both always run.
set -uo pipefail
cd "$(dirname "$0")/.."

bash tests/setup.sh || exit 1
cargo run --release --quiet --bin hsp -- package || exit 1

cargo test --release
rust=$?
.venv/bin/python -m pytest tests/python -q
python=$?

echo "cargo test: exit $rust; pytest: exit $python"
[ "$rust" -eq 0 ] && [ "$python" -eq 0 ]
