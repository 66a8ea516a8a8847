#!/usr/bin/env bash
# Installs what the tests need on a fresh Debian machine: libclang (for the `fmi` crate's
# bindings, a dev-dependency) and a Python virtual environment in .venv (ignored by git) with
# fmpy, libcosimpy, fmu_manipulation_toolbox, scipy and pytest. Safe to run again: it only
# installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

# bindgen (through clang-sys) dlopens libclang.so, libclang-N.so or libclang.so.N; test for exactly
# those names. libclang-cpp.so (the C++ interface, present on many machines) is a different library
# and must not pass for it: that mistake once skipped the install on a fresh machine.
have_libclang() {
    find /usr/lib /usr/local/lib -maxdepth 4 -regextype posix-extended \
        -regex '.*/libclang(-[0-9.]+)?\.so(\.[0-9]+)*' -print -quit 2>/dev/null | grep -q .
}
if ! have_libclang; then
    echo "setup: installing libclang-dev (apt)"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libclang-dev >/dev/null
fi

command -v chromium >/dev/null || { echo "setup: installing chromium (apt), for tests/python/test_docs.py"; S=""; [ "$(id -u)" -ne 0 ] && S=sudo; $S apt-get update -qq && DEBIAN_FRONTEND=noninteractive $S apt-get install -y -qq chromium >/dev/null; }
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import fmpy, libcosimpy, fmu_manipulation_toolbox, scipy, pytest, distributed, matplotlib" 2>/dev/null; then
    echo "setup: creating the Python virtual environment .venv"
    python3 -m venv .venv
    .venv/bin/pip install --quiet --upgrade pip
    .venv/bin/pip install --quiet -r tests/requirements.txt
fi
