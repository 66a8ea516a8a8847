//! Where the FMU's binaries come from (`hsp package`).
//!
//! | FMI 2.0 folder | FMI 3.0 folder | built with |
//! | --- | --- | --- |
//! | `linux64` | `x86_64-linux` | `cargo zigbuild --target x86_64-unknown-linux-gnu.2.17` |
//! | (none) | `aarch64-linux` | `cargo zigbuild --target aarch64-unknown-linux-gnu.2.17` |
//! | `win64` | `x86_64-windows` | `cargo build --target x86_64-pc-windows-gnu` (mingw-w64) |
//! | `darwin64` (universal: x86-64 and arm64) | `x86_64-darwin`, `aarch64-darwin` (one each) | `cargo zigbuild --target universal2-apple-darwin` |
//!
//! - The Linux binaries are built against glibc 2.17 with `cargo-zigbuild` (zig as the linker), so
//!   that they load on every Linux of the last decade (RHEL 7, Ubuntu 14.04 and later). Without
//!   that toolchain the x86-64 library is built for this machine's glibc, with a warning: it then
//!   loads only where glibc is at least as new, and there is no aarch64 one.
//! - FMI 2.0 names no folder for aarch64 Linux: its importers (fmpy, the FMI Library) look for
//!   every 64-bit Linux binary in `linux64`, which holds the x86-64 one. So the aarch64 Linux
//!   binary is in the FMI 3.0 FMU only.
//! - `binaries/win64`: cross-compiled with mingw-w64. It needs Windows 10 or later (Rust's
//!   standard library imports `ProcessPrng` from `bcryptprimitives.dll`).
//! - macOS: zig links against the `libSystem` stubs it ships (no Apple SDK needed; the library
//!   needs nothing else). zig would mark the binaries for its own default minimum macOS (15.0),
//!   and cargo-zigbuild gives zig no version, so `hsp` hands cargo-zigbuild a linker of its own
//!   ([`macos_linker`]) that names zig the version rustc compiles for (`rustc --print
//!   deployment-target`: 10.12 on x86-64, 11.0 on arm64). The arm64 slice carries the ad-hoc code
//!   signature Apple silicon requires; zig's linker writes it. FMI 2.0's `darwin64` gets the
//!   universal (fat) binary, which macOS importers load on either processor; FMI 3.0 names one
//!   folder per processor and gets the single-architecture binaries.
//!
//! `tests/setup.sh` installs every toolchain (zig and cargo-zigbuild into `.venv` from PyPI, the
//! Rust targets with rustup, mingw-w64 with apt). With `--require-portable` a missing toolchain is
//! an error instead of a warning: the project's test command packages that way, so CI cannot ship
//! an FMU that lacks a platform or whose Linux binary old systems would refuse.
//!
//! Every binary is the library alone, built with `--no-default-features`: the command-line tools'
//! dependencies (clap, zip, libc) stay out of the FMU.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::package::root;

/// The glibc the Linux binaries are built against (their newest symbol version may be older).
pub const LINUX_GLIBC: &str = "2.17";
const LINUX_TARGET: &str = "x86_64-unknown-linux-gnu";
const LINUX_AARCH64_TARGET: &str = "aarch64-unknown-linux-gnu";
const WINDOWS_TARGET: &str = "x86_64-pc-windows-gnu";
const MACOS_TARGETS: [&str; 2] = ["x86_64-apple-darwin", "aarch64-apple-darwin"];
/// cargo-zigbuild's name for the two macOS targets built together and joined into a fat binary.
const MACOS_UNIVERSAL_TARGET: &str = "universal2-apple-darwin";
const MINGW_GCC: &str = "x86_64-w64-mingw32-gcc";
/// The library's file stem as cargo names it.
const CRATE_LIB: &str = "hydraulic_slewing_plate";

/// One binary: its folders under `binaries/` in the FMI 2.0 and the FMI 3.0 FMU (`None`: not in
/// that FMU), its extension and the built file.
pub struct Binary {
    pub fmi2: Option<&'static str>,
    pub fmi3: Option<&'static str>,
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

fn rustc() -> String {
    std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into())
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

/// The library cargo builds for `target` (a Rust target, or cargo-zigbuild's universal one).
fn library(target: &str, extension: &str) -> Result<PathBuf, String> {
    built(
        target_dir()
            .join(target)
            .join("release")
            .join(format!("lib{CRATE_LIB}.{extension}")),
    )
}

/// Which binaries `hsp package` builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Portability {
    /// Every binary of the table above, or an error naming the missing toolchain
    /// (`--require-portable`, the test command's).
    Required,
    /// Every binary the installed toolchains allow; a missing toolchain is a warning and the
    /// x86-64 Linux binary is then built for this machine's glibc.
    IfInstalled,
    /// Only the x86-64 Linux binary for this machine (`--host-only`: the quick test loop, which
    /// skips the cross builds and the tests of their binaries).
    HostOnly,
}

/// Runs one build and says on stderr how long it took (docs/platforms.md quotes these times).
fn timed<T>(what: &str, build: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
    let start = std::time::Instant::now();
    let result = build()?;
    eprintln!(
        "hsp package: {what}: {:.0} s",
        start.elapsed().as_secs_f64()
    );
    Ok(result)
}

/// Builds the binaries `portability` asks for.
pub fn build(portability: Portability) -> Result<Vec<Binary>, String> {
    let mut binaries = vec![Binary {
        fmi2: Some("linux64"),
        fmi3: Some("x86_64-linux"),
        extension: "so",
        path: timed("binaries/linux64", || build_linux64(portability))?,
    }];
    if portability == Portability::HostOnly {
        return Ok(binaries);
    }
    let require_portable = portability == Portability::Required;
    let aarch64 = timed("binaries/aarch64-linux", || {
        build_linux_aarch64(require_portable)
    })?;
    if let Some(path) = aarch64 {
        binaries.push(Binary {
            fmi2: None,
            fmi3: Some("aarch64-linux"),
            extension: "so",
            path,
        });
    }
    if let Some(path) = timed("binaries/win64", || build_win64(require_portable))? {
        binaries.push(Binary {
            fmi2: Some("win64"),
            fmi3: Some("x86_64-windows"),
            extension: "dll",
            path,
        });
    }
    let macos = timed("the macOS binaries", || build_macos(require_portable))?;
    if let Some([universal, x86_64, aarch64]) = macos {
        for (fmi2, fmi3, path) in [
            (Some("darwin64"), None, universal),
            (None, Some("x86_64-darwin"), x86_64),
            (None, Some("aarch64-darwin"), aarch64),
        ] {
            binaries.push(Binary {
                fmi2,
                fmi3,
                extension: "dylib",
                path,
            });
        }
    }
    Ok(binaries)
}

/// A missing toolchain: an error with `--require-portable`, else a warning and no binary.
fn missing<T>(message: String, require_portable: bool) -> Result<Option<T>, String> {
    if require_portable {
        return Err(message);
    }
    eprintln!("warning: {message}");
    Ok(None)
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

const NO_ZIGBUILD: &str = "cargo-zigbuild (with the ziglang package) is not installed";

/// `cargo zigbuild` of the library for `target` (with a `.2.17`-style glibc suffix where wanted).
fn zigbuild_command(program: &Path, path: &std::ffi::OsStr, target: &str) -> Command {
    let mut command = Command::new(program);
    command
        .args(["zigbuild", "--release", "--lib", "--no-default-features"])
        .args(["--target", target, "--quiet"])
        .env("PATH", path)
        .env("CARGO", cargo());
    command
}

/// cargo-zigbuild and the Rust `targets`, or what is missing (the FMU then lacks `what`).
fn zig_toolchain(
    targets: &[&str],
    what: &str,
    require_portable: bool,
) -> Result<Option<(PathBuf, std::ffi::OsString)>, String> {
    let absent: Vec<&str> = targets
        .iter()
        .copied()
        .filter(|t| !has_rust_target(t))
        .collect();
    let zig = zigbuild();
    let problem = match (&zig, absent.is_empty()) {
        (Some(_), true) => return Ok(zig),
        (None, _) => NO_ZIGBUILD.to_string(),
        (Some(_), false) => format!(
            "the Rust target {} is not installed (`rustup target add {}`)",
            absent.join(" and "),
            absent.join(" ")
        ),
    };
    missing(
        format!("{problem}, so the FMU gets no {what}; `bash tests/setup.sh` installs it"),
        require_portable,
    )
}

fn build_linux64(portability: Portability) -> Result<PathBuf, String> {
    let zig = match portability {
        Portability::HostOnly => None,
        _ => zigbuild(),
    };
    if let Some((program, path)) = zig {
        let target = format!("{LINUX_TARGET}.{LINUX_GLIBC}");
        let command = zigbuild_command(&program, &path, &target);
        run(command, &format!("cargo zigbuild --target {target}"))?;
        return library(LINUX_TARGET, "so");
    }
    let missing = format!(
        "{NO_ZIGBUILD}, so binaries/linux64 cannot be built against glibc {LINUX_GLIBC}; \
         `bash tests/setup.sh` installs it into .venv"
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
    built(
        target_dir()
            .join("release")
            .join(format!("lib{CRATE_LIB}.so")),
    )
}

/// The aarch64 Linux binary (FMI 3.0's `aarch64-linux`), against glibc 2.17 like the x86-64 one.
fn build_linux_aarch64(require_portable: bool) -> Result<Option<PathBuf>, String> {
    let Some((program, path)) = zig_toolchain(
        &[LINUX_AARCH64_TARGET],
        "binaries/aarch64-linux",
        require_portable,
    )?
    else {
        return Ok(None);
    };
    let target = format!("{LINUX_AARCH64_TARGET}.{LINUX_GLIBC}");
    run(
        zigbuild_command(&program, &path, &target),
        &format!("cargo zigbuild --target {target}"),
    )?;
    library(LINUX_AARCH64_TARGET, "so").map(Some)
}

/// The macOS binaries: the universal one (FMI 2.0's `darwin64`), then the x86-64 and the arm64
/// one (FMI 3.0's `x86_64-darwin` and `aarch64-darwin`), all from one cargo-zigbuild run.
fn build_macos(require_portable: bool) -> Result<Option<[PathBuf; 3]>, String> {
    let Some((program, path)) = zig_toolchain(
        &MACOS_TARGETS,
        "binaries/darwin64, x86_64-darwin or aarch64-darwin",
        require_portable,
    )?
    else {
        return Ok(None);
    };
    let mut command = zigbuild_command(&program, &path, MACOS_UNIVERSAL_TARGET);
    for target in MACOS_TARGETS {
        let linker = macos_linker(&program, target, &deployment_target(target)?)?;
        let variable = format!(
            "CARGO_TARGET_{}_LINKER",
            target.to_uppercase().replace('-', "_")
        );
        // cargo-zigbuild keeps a linker that is already set, and still does the rest.
        command.env(variable, linker);
    }
    run(
        command,
        &format!("cargo zigbuild --target {MACOS_UNIVERSAL_TARGET}"),
    )?;
    Ok(Some([
        library(MACOS_UNIVERSAL_TARGET, "dylib")?,
        library(MACOS_TARGETS[0], "dylib")?,
        library(MACOS_TARGETS[1], "dylib")?,
    ]))
}

/// The minimum macOS version rustc compiles `target` for (`MACOSX_DEPLOYMENT_TARGET`, else its
/// default for the target), e.g. `11.0`.
fn deployment_target(target: &str) -> Result<String, String> {
    let out = Command::new(rustc())
        .args(["--print", "deployment-target", "--target", target])
        .output()
        .map_err(|e| format!("cannot run rustc --print deployment-target: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    text.trim()
        .strip_prefix("MACOSX_DEPLOYMENT_TARGET=")
        .filter(|v| out.status.success() && v.split('.').all(|p| p.parse::<u32>().is_ok()))
        .map(str::to_string)
        .ok_or_else(|| {
            format!(
                "rustc --print deployment-target --target {target} printed {:?}",
                text.trim()
            )
        })
}

/// A linker script for `target` (written under the target directory): cargo-zigbuild's `zig cc`,
/// as its own wrapper calls it, but with the minimum macOS version in zig's target
/// (`aarch64-macos.11.0-none`). cargo-zigbuild's wrapper names no version and drops rustc's, so
/// zig would otherwise mark the binary for its own default, newer than most Macs run.
fn macos_linker(program: &Path, target: &str, version: &str) -> Result<PathBuf, String> {
    let arch = target.split('-').next().unwrap_or(target);
    let zig_target = format!("{arch}-macos.{version}-none");
    let program = program.to_string_lossy();
    if program.contains('\'') {
        return Err(format!("cannot quote the path {program} in a shell script"));
    }
    let script = format!(
        "#!/bin/sh\n# Written by `hsp package` (src/bin/hsp/binaries.rs): the linker of {target}.\n\
         exec '{program}' zig cc -- -g -fno-sanitize=all -target {zig_target} \"$@\"\n"
    );
    let dir = target_dir().join("hsp-linkers");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let path = dir.join(format!("zigcc-{zig_target}.sh"));
    if std::fs::read_to_string(&path).ok().as_deref() != Some(script.as_str()) {
        std::fs::write(&path, script).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755))
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(path)
}

/// Whether rustup (or the toolchain) has the standard library for `target`.
fn has_rust_target(target: &str) -> bool {
    Command::new(rustc())
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
    let problem = match (has_rust_target(WINDOWS_TARGET), has_linker) {
        (true, true) => None,
        (false, _) => Some(format!(
            "the Rust target {WINDOWS_TARGET} is not installed (`rustup target add \
             {WINDOWS_TARGET}`)"
        )),
        (true, false) => Some(format!(
            "the mingw-w64 linker {MINGW_GCC} is not installed (Debian: gcc-mingw-w64-x86-64)"
        )),
    };
    if let Some(problem) = problem {
        return missing(
            format!(
                "{problem}, so the FMU gets no binaries/win64; `bash tests/setup.sh` installs both"
            ),
            require_portable,
        );
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
