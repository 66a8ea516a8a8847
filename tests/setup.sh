#!/usr/bin/env bash
# Installs what the build and the tests need on a fresh Debian machine that has a Rust toolchain
# (rustup) and Python 3. Safe to run again: it tests for the exact file each consumer loads or runs
# and installs only what is missing.
#
#   apt      libclang-dev          libclang.so, which bindgen dlopens (the `fmi` dev-dependency)
#            gcc-mingw-w64-x86-64  x86_64-w64-mingw32-gcc, the linker of binaries/win64 and the
#                                  compiler of the Wine test's driver (tests/portable/)
#            wine, wine64          /usr/bin/wine and /usr/lib/wine/wine64: run that test's driver
#            binutils              objdump, which reads the Linux binaries' glibc symbol versions
#            qemu-user             /usr/bin/qemu-aarch64: runs the aarch64 driver of that test on
#                                  binaries/aarch64-linux (user-mode emulation)
#            gcc-aarch64-linux-gnu aarch64-linux-gnu-gcc, the compiler of that driver
#            libc6-dev-arm64-cross its aarch64 crt files and libraries (/usr/aarch64-linux-gnu/lib),
#                                  and through libc6-arm64-cross the loader and libc.so.6 that
#                                  `qemu-aarch64 -L /usr/aarch64-linux-gnu` runs it with
#            python3-venv          only where python3 lacks the venv/ensurepip modules
#            chromium              /usr/bin/chromium: the headless browser of test_docs.py and
#                                  test_web.py
#            chromium-driver       /usr/bin/chromedriver, through which Selenium drives it
#                                  (test_web.py, bench/web_speed.py)
#            libtbb12              libtbb.so.12, which ecospy's libecosc.so needs (the ecos
#                                  co-simulation runs of test_shipped_sets.py)
#   rustup   x86_64-pc-windows-gnu      the Rust standard library for binaries/win64
#            aarch64-unknown-linux-gnu  ... for binaries/aarch64-linux (FMI 3.0)
#            x86_64-apple-darwin        ... for the macOS binaries (darwin64, x86_64-darwin,
#            aarch64-apple-darwin           aarch64-darwin), which rustc's own rust-lld links
#                                           against the ziglang package's libSystem stubs: no
#                                           Apple SDK needed
#            wasm32-unknown-unknown     the browser build (docs/web/hsp.wasm, `hsp web`)
#            wasm32-wasip2              the FMI 3.0 FMU's WebAssembly component
#                                       (binaries/wasm32-wasip2, fmi-ls-wasm)
#   .venv    tests/requirements.txt: fmpy, libcosimpy, ecospy, fmu_manipulation_toolbox, scipy, pytest,
#            pytest-timeout, selenium, wasmtime (the component's importer), and
#            the build tools ziglang and cargo-zigbuild (the Linux binaries against glibc 2.17;
#            ziglang's libSystem.tbd for the macOS binaries)
set -euo pipefail
cd "$(dirname "$0")/.."

RUST_TARGETS=(x86_64-pc-windows-gnu aarch64-unknown-linux-gnu x86_64-apple-darwin aarch64-apple-darwin
    wasm32-unknown-unknown wasm32-wasip2)
AARCH64_ROOT=/usr/aarch64-linux-gnu

# bindgen (through clang-sys) dlopens libclang.so, libclang-N.so or libclang.so.N; test for exactly
# those names. libclang-cpp.so (the C++ interface, present on many machines) is a different library
# and must not pass for it: that mistake once skipped the install on a fresh machine.
have_libclang() {
    find /usr/lib /usr/local/lib -maxdepth 4 -regextype posix-extended \
        -regex '.*/libclang(-[0-9.]+)?\.so(\.[0-9]+)*' -print -quit 2>/dev/null | grep -q .
}
have() { command -v "$1" >/dev/null 2>&1; }
# ecospy's libecosc.so is linked against libtbb.so.12 (oneTBB): the loader looks for that name.
have_libtbb() {
    find /usr/lib /usr/local/lib -maxdepth 3 -name 'libtbb.so.12' -print -quit 2>/dev/null | grep -q .
}

apt_packages=()
have_libclang || apt_packages+=(libclang-dev)
have x86_64-w64-mingw32-gcc || apt_packages+=(gcc-mingw-w64-x86-64)
{ have wine && [ -x /usr/lib/wine/wine64 ]; } || apt_packages+=(wine wine64)
have objdump || apt_packages+=(binutils)
have qemu-aarch64 || apt_packages+=(qemu-user)
have aarch64-linux-gnu-gcc || apt_packages+=(gcc-aarch64-linux-gnu)
{ [ -e "$AARCH64_ROOT/lib/crt1.o" ] && [ -e "$AARCH64_ROOT/lib/ld-linux-aarch64.so.1" ] &&
    [ -e "$AARCH64_ROOT/lib/libc.so.6" ]; } || apt_packages+=(libc6-dev-arm64-cross)
python3 -c "import venv, ensurepip" 2>/dev/null || apt_packages+=(python3-venv)
have chromium || apt_packages+=(chromium)  # headless browser of test_docs.py and test_web.py
have chromedriver || apt_packages+=(chromium-driver)  # Selenium's driver of that browser (test_web.py)
have_libtbb || apt_packages+=(libtbb12)  # ecospy's libecosc.so needs it (test_shipped_sets.py)
if [ "${#apt_packages[@]}" -gt 0 ]; then
    echo "setup: installing ${apt_packages[*]} (apt)"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
        "${apt_packages[@]}" >/dev/null
fi
have_libclang || { echo "setup: libclang.so still missing after installing libclang-dev" >&2; exit 1; }

# The standard library of each cross target, where rustc looks for it (the same test as
# `hsp package`).
for target in "${RUST_TARGETS[@]}"; do
    if [ ! -d "$(rustc --print sysroot)/lib/rustlib/$target/lib" ]; then
        if ! have rustup; then
            echo "setup: the Rust target $target is missing and rustup is not installed" >&2
            exit 1
        fi
        echo "setup: adding the Rust target $target (rustup)"
        rustup target add "$target"
    fi
done

venv_complete() {
    [ -x .venv/bin/python ] && [ -x .venv/bin/cargo-zigbuild ] &&
        .venv/bin/python -c "import fmpy, libcosimpy, ecospy, fmu_manipulation_toolbox, scipy, pytest, pytest_timeout, distributed, matplotlib, selenium, wasmtime.component" 2>/dev/null &&
        .venv/bin/python -m ziglang version >/dev/null 2>&1
}
if ! venv_complete; then
    echo "setup: installing the Python virtual environment .venv (tests/requirements.txt)"
    [ -x .venv/bin/python ] || python3 -m venv .venv
    .venv/bin/pip install --quiet --upgrade pip
    .venv/bin/pip install --quiet -r tests/requirements.txt
    venv_complete || { echo "setup: .venv is still incomplete after pip install" >&2; exit 1; }
fi
