//! Where the FMU's binaries come from (`hsp package`).
//!
//! | FMI 2.0 folder | FMI 3.0 folder | built with |
//! | --- | --- | --- |
//! | `linux64` | `x86_64-linux` | `cargo zigbuild --target x86_64-unknown-linux-gnu.2.17` |
//! | (none) | `aarch64-linux` | `cargo zigbuild --target aarch64-unknown-linux-gnu.2.17` |
//! | `win64` | `x86_64-windows` | `cargo build --target x86_64-pc-windows-gnu` (mingw-w64) |
//! | `darwin64` (universal: x86-64 and arm64) | `x86_64-darwin`, `aarch64-darwin` (one each) | `cargo rustc --target {x86_64,aarch64}-apple-darwin` with `ld64.lld` |
//! | (none) | `wasm32-wasip2` (a WebAssembly component, fmi-ls-wasm) | `cargo build --target wasm32-wasip2` |
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
//! - macOS: linked by LLVM's `ld64.lld` (`rust-lld`, shipped with rustc) against the `libSystem`
//!   stubs of the `ziglang` package, so no Apple SDK is needed (the library needs nothing else
//!   from macOS); see [`build_macos`]. The minimum macOS is rustc's for each target (`rustc --print
//!   deployment-target`: 10.12 on x86-64, 11.0 on arm64), and the arm64 library carries the
//!   ad-hoc code signature Apple silicon requires. FMI 2.0's `darwin64` gets one universal (fat)
//!   binary of both, which macOS importers load on either processor ([`write_universal`]); FMI
//!   3.0 names one folder per processor and gets the single-architecture binaries.
//! - `wasm32-wasip2`: the FMI 3.0 FMU as a WebAssembly component after the draft layered standard
//!   fmi-ls-wasm (`hydraulic_slewing_plate::fmi3::component`, its WIT in `src/fmi3/wit/`), with the
//!   layered standard's manifest in `extra/org.modelica.fmi-ls-wasm/` ([`super::ecosystem::ls_wasm`]).
//!   FMI 2.0 has no such platform.
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
use hydraulic_slewing_plate::model::variables::MODEL_IDENTIFIER;

/// The glibc the Linux binaries are built against (their newest symbol version may be older).
pub const LINUX_GLIBC: &str = "2.17";
const LINUX_TARGET: &str = "x86_64-unknown-linux-gnu";
const LINUX_AARCH64_TARGET: &str = "aarch64-unknown-linux-gnu";
const WINDOWS_TARGET: &str = "x86_64-pc-windows-gnu";
/// The WebAssembly component's target (fmi-ls-wasm's platform folder has its name).
pub const WASI_TARGET: &str = "wasm32-wasip2";
const MACOS_TARGETS: [&str; 2] = ["x86_64-apple-darwin", "aarch64-apple-darwin"];
/// Where the universal macOS binary is written, under the target directory.
const MACOS_UNIVERSAL_DIR: &str = "universal-apple-darwin/release";
const MINGW_GCC: &str = "x86_64-w64-mingw32-gcc";
/// Where the x86-64 Linux library for this machine's glibc is built, under the target directory
/// (without zig, and with `--host-only`).
const HOST_FMU_DIR: &str = "fmu-host";
/// The library's file stem as cargo names it.
const CRATE_LIB: &str = "hydraulic_slewing_plate";

/// One binary: its folders under `binaries/` in the FMI 2.0 and the FMI 3.0 FMU (`None`: not in
/// that FMU), the Rust target it is built for (the universal macOS file: its x86-64 one; the
/// arm64 slice is the `aarch64-darwin` binary's), its extension and the built file.
pub struct Binary {
    pub fmi2: Option<&'static str>,
    pub fmi3: Option<&'static str>,
    pub target: &'static str,
    pub extension: &'static str,
    pub path: PathBuf,
}

pub(super) fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target"))
}

pub(super) fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".into())
}

fn rustc() -> String {
    std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into())
}

/// Runs a build command in the repository root; the error names the command.
pub(super) fn run(mut command: Command, what: &str) -> Result<(), String> {
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

pub(super) fn built(path: PathBuf) -> Result<PathBuf, String> {
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
pub(super) fn timed<T>(what: &str, build: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
    timed_optional(what, || build().map(Some)).map(|built| built.expect("always built"))
}

/// [`timed`] for a build that a missing toolchain skips (`None`): only a made binary's time is
/// said (the skip has its warning).
fn timed_optional<T>(
    what: &str,
    build: impl FnOnce() -> Result<Option<T>, String>,
) -> Result<Option<T>, String> {
    let start = std::time::Instant::now();
    let result = build()?;
    if result.is_some() {
        eprintln!(
            "hsp package: {what}: {:.0} s",
            start.elapsed().as_secs_f64()
        );
    }
    Ok(result)
}

/// Builds the binaries `portability` asks for.
pub fn build(portability: Portability) -> Result<Vec<Binary>, String> {
    let mut binaries = vec![Binary {
        fmi2: Some("linux64"),
        fmi3: Some("x86_64-linux"),
        target: LINUX_TARGET,
        extension: "so",
        path: timed("binaries/linux64", || build_linux64(portability))?,
    }];
    if portability == Portability::HostOnly {
        return Ok(binaries);
    }
    let require_portable = portability == Portability::Required;
    let aarch64 = timed_optional("binaries/aarch64-linux", || {
        build_linux_aarch64(require_portable)
    })?;
    if let Some(path) = aarch64 {
        binaries.push(Binary {
            fmi2: None,
            fmi3: Some("aarch64-linux"),
            target: LINUX_AARCH64_TARGET,
            extension: "so",
            path,
        });
    }
    if let Some(path) = timed_optional("binaries/win64", || build_win64(require_portable))? {
        binaries.push(Binary {
            fmi2: Some("win64"),
            fmi3: Some("x86_64-windows"),
            target: WINDOWS_TARGET,
            extension: "dll",
            path,
        });
    }
    if let Some(path) = timed_optional("binaries/wasm32-wasip2", || {
        build_wasm_component(require_portable)
    })? {
        binaries.push(Binary {
            fmi2: None,
            fmi3: Some(WASI_TARGET),
            target: WASI_TARGET,
            extension: "wasm",
            path,
        });
    }
    let macos = timed_optional("the macOS binaries", || build_macos(require_portable))?;
    if let Some([universal, x86_64, aarch64]) = macos {
        let [x86_64_target, aarch64_target] = MACOS_TARGETS;
        for (fmi2, fmi3, target, path) in [
            (Some("darwin64"), None, x86_64_target, universal),
            (None, Some("x86_64-darwin"), x86_64_target, x86_64),
            (None, Some("aarch64-darwin"), aarch64_target, aarch64),
        ] {
            binaries.push(Binary {
                fmi2,
                fmi3,
                target,
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

/// What is missing when the Rust `targets` (one or more) are absent, and the command that adds them.
pub(super) fn not_installed(targets: &[&str]) -> String {
    let (noun, verb) = if targets.len() == 1 {
        ("target", "is")
    } else {
        ("targets", "are")
    };
    format!(
        "the Rust {noun} {} {verb} not installed (`rustup target add {}`)",
        targets.join(" and "),
        targets.join(" ")
    )
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
        (Some(_), false) => not_installed(&absent),
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
    // A target directory of its own: the FMU's library (without the `cli` feature) and the one
    // `hsp` links (with it) share one fingerprint in cargo's `target/release`, so building one
    // there made cargo rebuild the other at the next `cargo run --bin hsp`, minutes each time.
    let host_dir = target_dir().join(HOST_FMU_DIR);
    let mut command = cargo_build_library();
    command.arg("--target-dir").arg(&host_dir);
    run(command, "cargo build --release --lib")?;
    built(host_dir.join("release").join(format!("lib{CRATE_LIB}.so")))
}

/// `cargo build` of the FMU's library alone: release, without the tools' `cli` feature.
fn cargo_build_library() -> Command {
    let mut command = Command::new(cargo());
    command.args([
        "build",
        "--release",
        "--lib",
        "--no-default-features",
        "--quiet",
    ]);
    command
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
/// one (FMI 3.0's `x86_64-darwin` and `aarch64-darwin`).
///
/// Each is linked by LLVM's Mach-O linker `ld64.lld` (`rust-lld`, which rustup ships with rustc)
/// against a minimal SDK ([`macos_sdk`]); rustc gives it the minimum macOS, the SDK version and
/// the list of symbols to export (the `fmi2*` and `fmi3*` functions), and it signs the arm64
/// library ad hoc. Not zig's linker: zig 0.17 ignores the export list, so its dylibs export every
/// Rust symbol of the library as well.
fn build_macos(require_portable: bool) -> Result<Option<[PathBuf; 3]>, String> {
    let absent: Vec<&str> = MACOS_TARGETS
        .iter()
        .copied()
        .filter(|t| !has_rust_target(t))
        .collect();
    let what = "binaries/darwin64, x86_64-darwin or aarch64-darwin";
    if !absent.is_empty() {
        return missing(
            format!(
                "{}, so the FMU gets no {what}; `bash tests/setup.sh` installs it",
                not_installed(&absent)
            ),
            require_portable,
        );
    }
    if !has_rust_lld() {
        return missing(
            format!(
                "rustc's linker rust-lld is not installed (it comes with rustup's rustc), so the \
                 FMU gets no {what}"
            ),
            require_portable,
        );
    }
    let Some(sdk) = macos_sdk()? else {
        return missing(
            format!(
                "the ziglang package (whose libSystem stubs the macOS binaries link against) is \
                 not installed, so the FMU gets no {what}; `bash tests/setup.sh` installs it into \
                 .venv"
            ),
            require_portable,
        );
    };
    let install_name = format!("@rpath/{MODEL_IDENTIFIER}.dylib");
    let mut thin = Vec::new();
    for target in MACOS_TARGETS {
        let mut command = Command::new(cargo());
        command
            .args([
                "rustc",
                "--release",
                "--lib",
                "--no-default-features",
                "--quiet",
            ])
            .args(["--target", target, "--"])
            .args(["-C", "linker=rust-lld", "-C", "linker-flavor=ld64.lld"])
            // The install name (LC_ID_DYLIB): the library's name in the FMU, not the path of the
            // build directory, which the linker would otherwise write into it.
            .args(["-C", "link-arg=-install_name", "-C"])
            .arg(format!("link-arg={install_name}"))
            .env("SDKROOT", &sdk);
        run(
            command,
            &format!("cargo rustc --target {target} (ld64.lld)"),
        )?;
        thin.push(library(target, "dylib")?);
    }
    let universal = target_dir()
        .join(MACOS_UNIVERSAL_DIR)
        .join(format!("lib{CRATE_LIB}.dylib"));
    write_universal(&universal, &thin)?;
    let [x86_64, aarch64] = <[PathBuf; 2]>::try_from(thin).map_err(|_| "two macOS targets")?;
    Ok(Some([universal, x86_64, aarch64]))
}

/// A minimal macOS SDK for the linker, under the target directory: `usr/lib/libSystem.tbd` (the
/// text stub listing what `/usr/lib/libSystem.B.dylib` exports), made from the one the `ziglang`
/// package ships, and `libc`, `libm`, `libpthread`, `libdl` and `libiconv` as its aliases (as in
/// Apple's SDK, where they are libSystem too). `None` without the ziglang package.
///
/// zig's stub names its Apple silicon targets `arm64e` and `arm64e.x1`, which ld64.lld does not
/// read, and no plain `arm64` (zig treats them as one); here `arm64e` becomes `arm64` and the
/// `arm64e.x1` entries go. The symbols are those of arm64e, which macOS's libSystem exports on
/// arm64 alike.
fn macos_sdk() -> Result<Option<PathBuf>, String> {
    let venv_python = root().join(".venv/bin/python3");
    let python = if venv_python.is_file() {
        venv_python
    } else {
        PathBuf::from("python3")
    };
    let Some(ziglang) = Command::new(python)
        .args([
            "-c",
            "import pathlib, ziglang; print(pathlib.Path(ziglang.__file__).parent)",
        ])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| PathBuf::from(String::from_utf8_lossy(&o.stdout).trim()))
    else {
        return Ok(None);
    };
    let stub = ziglang.join("lib/libc/darwin/libSystem.tbd");
    let text = std::fs::read_to_string(&stub).map_err(|e| format!("{}: {e}", stub.display()))?;
    let sdk = target_dir().join("hsp-macos-sdk");
    let lib = sdk.join("usr/lib");
    std::fs::create_dir_all(&lib).map_err(|e| format!("{}: {e}", lib.display()))?;
    let text = apple_silicon_as_arm64(&text);
    for name in ["System", "c", "m", "pthread", "dl", "iconv"] {
        let path = lib.join(format!("lib{name}.tbd"));
        if std::fs::read_to_string(&path).ok().as_deref() != Some(text.as_str()) {
            std::fs::write(&path, &text).map_err(|e| format!("{}: {e}", path.display()))?;
        }
    }
    Ok(Some(sdk))
}

/// A text stub's target lists with `arm64e-…` as `arm64-…` and without `arm64e.x1-…` (see
/// [`macos_sdk`]); everything else as it was.
fn apple_silicon_as_arm64(tbd: &str) -> String {
    let mut out = String::with_capacity(tbd.len());
    let mut rest = tbd;
    while let Some(open) = rest.find('[') {
        let Some(close) = rest[open..].find(']').map(|c| open + c) else {
            break;
        };
        out.push_str(&rest[..=open]);
        let items: Vec<String> = rest[open + 1..close]
            .split(',')
            .map(str::trim)
            .filter(|item| !item.is_empty() && !item.starts_with("arm64e.x1-"))
            .map(|item| match item.strip_prefix("arm64e-") {
                Some(platform) => format!("arm64-{platform}"),
                None => item.to_string(),
            })
            .collect();
        out.push(' ');
        out.push_str(&items.join(", "));
        out.push_str(" ]");
        rest = &rest[close + 1..];
    }
    out.push_str(rest);
    out
}

/// Writes a universal (fat) Mach-O file of the single-architecture files `slices`: the big-endian
/// header (`FAT_MAGIC`, then per slice its CPU type and subtype, offset, size and alignment) and
/// each slice on a 16 KiB boundary, the page size of arm64 macOS, as `lipo` lays them out.
fn write_universal(path: &Path, slices: &[PathBuf]) -> Result<(), String> {
    const ALIGN_LOG2: u32 = 14;
    const MH_MAGIC_64: u32 = 0xFEED_FACF;
    let align = 1usize << ALIGN_LOG2;
    let mut data = Vec::new();
    for slice in slices {
        let bytes = std::fs::read(slice).map_err(|e| format!("{}: {e}", slice.display()))?;
        let word = |at: usize| {
            bytes
                .get(at..at + 4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        if word(0) != Some(MH_MAGIC_64) {
            return Err(format!("{} is not a 64-bit Mach-O file", slice.display()));
        }
        let (cputype, cpusubtype) = (word(4).unwrap_or(0), word(8).unwrap_or(0));
        data.push((cputype, cpusubtype, bytes));
    }
    let mut out = Vec::new();
    out.extend_from_slice(&0xCAFE_BABEu32.to_be_bytes());
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let mut offset = align; // the header fits in the first page
    let mut layout = Vec::new();
    for (cputype, cpusubtype, bytes) in &data {
        for field in [
            *cputype,
            *cpusubtype,
            offset as u32,
            bytes.len() as u32,
            ALIGN_LOG2,
        ] {
            out.extend_from_slice(&field.to_be_bytes());
        }
        layout.push(offset);
        offset = (offset + bytes.len()).div_ceil(align) * align;
    }
    for ((_, _, bytes), at) in data.iter().zip(layout) {
        out.resize(at, 0);
        out.extend_from_slice(bytes);
    }
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    std::fs::write(path, out).map_err(|e| format!("{}: {e}", path.display()))
}

/// Whether rustc has its own copy of LLVM's linker, `rust-lld` (in `lib/rustlib/<host>/bin` of
/// its sysroot, where rustc looks for it).
fn has_rust_lld() -> bool {
    let sysroot = Command::new(rustc())
        .args(["--print", "sysroot"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| PathBuf::from(String::from_utf8_lossy(&o.stdout).trim()));
    let host = Command::new(rustc())
        .args(["--print", "host-tuple"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());
    match (sysroot, host) {
        (Some(sysroot), Some(host)) => sysroot
            .join("lib/rustlib")
            .join(host)
            .join("bin/rust-lld")
            .is_file(),
        _ => false,
    }
}

/// Whether rustup (or the toolchain) has the standard library for `target`.
pub(super) fn has_rust_target(target: &str) -> bool {
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
        (false, _) => Some(not_installed(&[WINDOWS_TARGET])),
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
    cargo_build_for(WINDOWS_TARGET, &format!("{CRATE_LIB}.dll")).map(Some)
}

/// `cargo build` of the FMU's library for `target`, and the built `file`.
fn cargo_build_for(target: &str, file: &str) -> Result<PathBuf, String> {
    let mut command = cargo_build_library();
    command.args(["--target", target]);
    run(command, &format!("cargo build --target {target}"))?;
    built(target_dir().join(target).join("release").join(file))
}

/// The FMI 3.0 FMU's WebAssembly component (`binaries/wasm32-wasip2`). Rust's `wasm32-wasip2`
/// target links a component by itself (`wasm-component-ld`, shipped with the target), from the
/// bindings `wit-bindgen` generates of `src/fmi3/wit/`.
fn build_wasm_component(require_portable: bool) -> Result<Option<PathBuf>, String> {
    if !has_rust_target(WASI_TARGET) {
        return missing(
            format!(
                "{}, so the FMI 3.0 FMU gets no binaries/{WASI_TARGET}; `bash tests/setup.sh` \
                 installs it",
                not_installed(&[WASI_TARGET])
            ),
            require_portable,
        );
    }
    cargo_build_for(WASI_TARGET, &format!("{CRATE_LIB}.wasm")).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn apple_silicon_targets_become_arm64_and_symbols_stay() {
        let zig = "targets:         [ x86_64-macos, x86_64-maccatalyst, arm64e-macos, arm64e-maccatalyst, \n\
                   arm64e.x1-macos, arm64e.x1-maccatalyst ]\nsymbols: [ _sin, _arm64e_thing ]\n";
        assert_eq!(
            apple_silicon_as_arm64(zig),
            "targets:         [ x86_64-macos, x86_64-maccatalyst, arm64-macos, arm64-maccatalyst ]\n\
             symbols: [ _sin, _arm64e_thing ]\n"
        );
    }

    #[test]
    fn a_universal_file_holds_each_slice_on_a_16_kib_boundary() {
        let dir = std::env::temp_dir().join(format!("hsp-fat-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let slice = |cpu: u32, len: usize| {
            let mut b = vec![7u8; len];
            b[..4].copy_from_slice(&0xFEED_FACFu32.to_le_bytes());
            b[4..8].copy_from_slice(&cpu.to_le_bytes());
            b[8..12].copy_from_slice(&3u32.to_le_bytes());
            let path = dir.join(format!("{cpu:x}"));
            std::fs::write(&path, &b).unwrap();
            (path, b)
        };
        let (a, bytes_a) = slice(0x0100_0007, 20_000);
        let (b, bytes_b) = slice(0x0100_000C, 100);
        let fat = dir.join("fat");
        write_universal(&fat, &[a.clone(), b]).unwrap();
        let data = std::fs::read(&fat).unwrap();
        let be = |at: usize| u32::from_be_bytes(data[at..at + 4].try_into().unwrap());
        assert_eq!((be(0), be(4)), (0xCAFE_BABE, 2));
        // x86-64 at 16 KiB, arm64 at the next 16 KiB boundary after it (20 000 bytes: 48 KiB).
        assert_eq!(
            [be(8), be(12), be(16), be(20), be(24)],
            [0x0100_0007, 3, 16384, 20_000, 14]
        );
        assert_eq!([be(28), be(36), be(40)], [0x0100_000C, 49152, 100]);
        assert_eq!(&data[16384..16384 + 20_000], &bytes_a[..]);
        assert_eq!(&data[49152..], &bytes_b[..]);
        std::fs::write(&a, b"not mach-o").unwrap();
        assert!(write_universal(&fat, &[a]).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
