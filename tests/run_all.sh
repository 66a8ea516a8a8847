#!/usr/bin/env bash
# The project's test command: installs what is missing (tests/setup.sh), builds the FMU with its
# portable binaries (glibc-2.17 Linux on x86-64 and aarch64, Windows, macOS; `--require-portable`
# makes a missing toolchain an error rather than a warning), then runs the Rust tests (cargo test)
# and the import-side Python tests (pytest: fmpy, libcosim, fmutool, the examples, and the glibc,
# Wine, qemu and Mach-O checks of test_portable.py). Fails if either fails; both always run.
#
#   bash tests/run_all.sh           everything (CI runs this)
#   bash tests/run_all.sh --quick   the contributor's inner loop: the FMU with the Linux binary
#                                   for this machine only (`hsp package --host-only`, no glibc-2.17
#                                   or other cross build), every Rust test built in the `quick`
#                                   profile (no LTO, incremental) and every Python test but the
#                                   portable ones (test_portable.py, which needs those binaries)
# Both build the Rust tests in the `quick` profile (no LTO).
set -uo pipefail
cd "$(dirname "$0")/.."

quick=0
case "${1:-}" in
    "") ;;
    --quick) quick=1 ;;
    *) echo "usage: bash tests/run_all.sh [--quick]" >&2; exit 2 ;;
esac

bash tests/setup.sh || exit 1
if [ "$quick" -eq 1 ]; then
    cargo run --release --quiet --bin hsp -- package --host-only || exit 1
    pytest_skip=(--ignore tests/python/test_portable.py)
    # The Rust tests in Cargo.toml's `quick` profile: release optimisations without LTO,
    # incremental, so that a change recompiles in seconds (the FMU above is a release build).
    test_profile=(--profile quick)
else
    cargo run --release --quiet --bin hsp -- package --require-portable || exit 1
    pytest_skip=()
    # The Rust tests in the `quick` profile too: the release optimisations without link-time
    # optimisation, which would otherwise run for each of the ~50 test binaries (the FMU the
    # Python tests load is the release build above). Rust does no fast-math, so the numbers are
    # the release build's: the default experiment's reference CSV is checked bit for bit.
    test_profile=(--profile quick)
fi

cargo test "${test_profile[@]}" --no-fail-fast
rust=$?
# A test that hangs fails after 10 minutes with its name and stacks, so the other tests still
# run and CI ends (the slowest test, the qemu run of test_portable.py, takes about 11 s).
.venv/bin/python -m pytest tests/python -q --durations=10 --timeout=600 "${pytest_skip[@]}"
python=$?

echo "cargo test: exit $rust; pytest: exit $python"
[ "$rust" -eq 0 ] && [ "$python" -eq 0 ]
