#!/usr/bin/env bash
# The project's test command: installs what is missing (tests/setup.sh), builds the FMU with its
# portable binaries (glibc-2.17 Linux and Windows; `--require-portable` makes a missing toolchain
# an error rather than a warning), then runs the Rust tests (cargo test) and the import-side Python
# tests (pytest: fmpy, libcosim, fmutool, and the glibc and Wine checks of test_portable.py).
# Fails if either fails; both always run.
set -uo pipefail
cd "$(dirname "$0")/.."

bash tests/setup.sh || exit 1
cargo run --release --quiet --bin hsp -- package --require-portable || exit 1

cargo test --release --no-fail-fast
rust=$?
.venv/bin/python -m pytest tests/python -q
python=$?

echo "cargo test: exit $rust; pytest: exit $python"
[ "$rust" -eq 0 ] && [ "$python" -eq 0 ]
