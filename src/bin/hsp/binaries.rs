//! Where the FMU's binaries come from (`hsp package`).
//!
//! - `binaries/linux64`: built against glibc 2.17 with `cargo-zigbuild` (zig as the linker, target
//!   `x86_64-unknown-linux-gnu.2.17`), so that it loads on every Linux of the last decade (RHEL 7,
//!   Ubuntu 14.04 and later). Without that toolchain the library is built for this machine's glibc,
//!   with a warning: it then loads only where glibc is at least as new.
//! - `binaries/win64`: cross-compiled for `x86_64-pc-windows-gnu` with mingw-w64, when that Rust
//!   target and the linker are installed; skipped with a warning otherwise. It needs Windows 10 or
//!   later (Rust's standard library imports `ProcessPrng` from `bcryptprimitives.dll`).
//!
//! `tests/setup.sh` installs both toolchains (zig and cargo-zigbuild into `.venv` from PyPI, the
//! Rust target with rustup, mingw-w64 with apt). With `--require-portable` a missing toolchain is an
//! error instead of a warning: the project's test command packages that way, so CI cannot ship a
//! binary that old systems or Windows would refuse.
//!
//! Every binary is the library alone, built with `--no-default-features`: the command-line tools'
//! dependencies (clap, zip, libc) stay out of the FMU.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::package::root;

/// The glibc the Linux binary is built against (its newest symbol version may be older).
pub const LINUX_GLIBC: &str = "2.17";
const LINUX_TARGET: &str = "x86_64-unknown-linux-gnu";
const WINDOWS_TARGET: &str = "x86_64-pc-windows-gnu";
const MINGW_GCC: &str = "x86_64-w64-mingw32-gcc";
/// The library's file stem as cargo names it.
const CRATE_LIB: &str = "hydraulic_slewing_plate";

/// One platform's binary: its folder under `binaries/`, its extension and the built file.
pub struct Binary {
    pub platform: &'static str,
    pub extension: &'static str,
    pub path: PathBuf,
}

fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target"))
}

fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".into())
}

/// Runs a build command in the repository root; the error names the command.
fn run(mut command: Command, what: &str) -> Result<(), String> {
    let status = command
        .current_dir(root())
        .status()
        .map_err(|e| format!("cannot run {what}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{what} failed ({status})"))
    }
}

fn built(path: PathBuf) -> Result<PathBuf, String> {
    if path.exists() {
        Ok(path)
    } else {
        Err(format!("{} was not built", path.display()))
    }
}

/// Which binaries `hsp package` builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Portability {
    /// The glibc-2.17 Linux binary and the Windows binary, or an error naming the missing
    /// toolchain (`--require-portable`, the test command's).
    Required,
    /// Every binary the installed toolchains allow; a missing toolchain is a warning and the
    /// Linux binary is then built for this machine's glibc.
    IfInstalled,
    /// Only the Linux binary for this machine (`--host-only`: the quick test loop, which skips
    /// the two cross builds and the tests of their binaries).
    HostOnly,
}

/// Builds the binaries `portability` asks for.
pub fn build(portability: Portability) -> Result<Vec<Binary>, String> {
    let require_portable = portability == Portability::Required;
    let mut binaries = vec![Binary {
        platform: "linux64",
        extension: "so",
        path: build_linux64(portability)?,
    }];
    if portability == Portability::HostOnly {
        return Ok(binaries);
    }
    if let Some(path) = build_win64(require_portable)? {
        binaries.push(Binary {
            platform: "win64",
            extension: "dll",
            path,
        });
    }
    Ok(binaries)
}

/// `cargo-zigbuild` from the checkout's `.venv` (where `tests/setup.sh` puts it, beside the `ziglang`
/// package it runs zig from), else from `PATH`. Returns the program and the `PATH` to run it with.
fn zigbuild() -> Option<(PathBuf, std::ffi::OsString)> {
    let venv_bin = root().join(".venv/bin");
    let path = std::env::var_os("PATH").unwrap_or_default();
    // The venv first on PATH, so that cargo-zigbuild's `python3 -m ziglang` finds the venv's zig.
    let with_venv =
        std::env::join_paths(std::iter::once(venv_bin.clone()).chain(std::env::split_paths(&path)))
            .ok()?;
    let program = if venv_bin.join("cargo-zigbuild").is_file() {
        venv_bin.join("cargo-zigbuild")
    } else {
        PathBuf::from("cargo-zigbuild")
    };
    let works = Command::new(&program)
        .arg("--version")
        .env("PATH", &with_venv)
        .output()
        .is_ok_and(|o| o.status.success());
    works.then_some((program, with_venv))
}

fn build_linux64(portability: Portability) -> Result<PathBuf, String> {
    let library = format!("lib{CRATE_LIB}.so");
    let zig = match portability {
        Portability::HostOnly => None,
        _ => zigbuild(),
    };
    if let Some((program, path)) = zig {
        let target = format!("{LINUX_TARGET}.{LINUX_GLIBC}");
        let mut command = Command::new(&program);
        command
            .args(["zigbuild", "--release", "--lib", "--no-default-features"])
            .args(["--target", &target, "--quiet"])
            .env("PATH", path)
            .env("CARGO", cargo());
        run(command, &format!("cargo zigbuild --target {target}"))?;
        return built(
            target_dir()
                .join(LINUX_TARGET)
                .join("release")
                .join(library),
        );
    }
    let missing = format!(
        "cargo-zigbuild (with the ziglang package) is not installed, so binaries/linux64 cannot be \
         built against glibc {LINUX_GLIBC}; `bash tests/setup.sh` installs it into .venv"
    );
    match portability {
        Portability::Required => return Err(missing),
        Portability::IfInstalled => eprintln!(
            "warning: {missing}. Building for this machine's glibc instead: the FMU will not load \
             on systems with an older glibc."
        ),
        Portability::HostOnly => {}
    }
    let mut command = Command::new(cargo());
    command.args([
        "build",
        "--release",
        "--lib",
        "--no-default-features",
        "--quiet",
    ]);
    run(command, "cargo build --release --lib")?;
    built(target_dir().join("release").join(library))
}

/// Whether rustup (or the toolchain) has the standard library for `target`.
fn has_rust_target(target: &str) -> bool {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    Command::new(rustc)
        .args(["--print", "sysroot"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .is_some_and(|sysroot| {
            Path::new(&sysroot)
                .join("lib/rustlib")
                .join(target)
                .join("lib")
                .is_dir()
        })
}

fn build_win64(require_portable: bool) -> Result<Option<PathBuf>, String> {
    let has_linker = Command::new(MINGW_GCC)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    let missing = match (has_rust_target(WINDOWS_TARGET), has_linker) {
        (true, true) => None,
        (false, _) => Some(format!(
            "the Rust target {WINDOWS_TARGET} is not installed (`rustup target add \
             {WINDOWS_TARGET}`)"
        )),
        (true, false) => Some(format!(
            "the mingw-w64 linker {MINGW_GCC} is not installed (Debian: gcc-mingw-w64-x86-64)"
        )),
    };
    if let Some(missing) = missing {
        let message = format!(
            "{missing}, so the FMU gets no binaries/win64; `bash tests/setup.sh` installs both"
        );
        if require_portable {
            return Err(message);
        }
        eprintln!("warning: {message}");
        return Ok(None);
    }
    let mut command = Command::new(cargo());
    command
        .args([
            "build",
            "--release",
            "--lib",
            "--no-default-features",
            "--quiet",
        ])
        .args(["--target", WINDOWS_TARGET]);
    run(command, &format!("cargo build --target {WINDOWS_TARGET}"))?;
    built(
        target_dir()
            .join(WINDOWS_TARGET)
            .join("release")
            .join(format!("{CRATE_LIB}.dll")),
    )
    .map(Some)
}
