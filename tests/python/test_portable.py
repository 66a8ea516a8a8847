"""The FMU's binaries on other systems than the build machine.

- binaries/linux64 is linked against glibc 2.17 (hsp package, cargo-zigbuild): objdump -T lists no
  symbol version above GLIBC_2.17 and objdump -p needs no library outside glibc.
- binaries/win64 (cross-compiled with mingw-w64) exports the FMI functions, imports only system
  DLLs, and under Wine runs the default experiment to the same result as the Linux library: the
  same driver (tests/portable/driver.c) is built for both with gcc and mingw-w64.
- binaries/aarch64-linux (FMI 3.0 FMU only) is linked against glibc 2.17 too, and the same driver,
  built with aarch64-linux-gnu-gcc, runs it under qemu-aarch64 (user-mode emulation) to the same
  result as the x86-64 library.
- The macOS binaries (FMI 2.0's universal darwin64, FMI 3.0's x86_64-darwin and aarch64-darwin)
  cannot run here; their Mach-O files are read by hand: architectures, exported FMI functions,
  libSystem as the only library, the minimum macOS, and the arm64 slice's ad-hoc signature.

What this does not test: Windows itself (Wine is not Windows: its loader, its C runtime and its
math library differ; the DLL imports ProcessPrng from bcryptprimitives.dll, which Windows 10 and
later have and Debian's Wine 8 lacks, so a test-only shim stands in for it here,
tests/portable/bcryptprimitives_shim.c), importers other than this driver on Windows, old
Linux distributions themselves (only the symbol versions the library asks for), aarch64 hardware
(qemu emulates it), and macOS at all (nothing here loads a Mach-O file).

Every tool comes from tests/setup.sh; a missing one fails the test with what to install."""

import hashlib
import os
import pathlib
import re
import shutil
import struct
import subprocess
import zipfile

import pytest

from conftest import packaged_source_hash, preset

ROOT = pathlib.Path(__file__).resolve().parents[2]
PORTABLE = ROOT / "tests" / "portable"
MAX_GLIBC = (2, 17)
# The libraries of glibc itself: before 2.34, threads, dlopen and clocks lived in their own files.
GLIBC_LIBRARIES = {"libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2", "librt.so.1",
                   "ld-linux-x86-64.so.2"}
# DLLs that every Windows 10 has. Not allowed: mingw's runtime DLLs (libgcc_s_seh-1.dll,
# libwinpthread-1.dll), which a user's machine does not have.
WINDOWS_SYSTEM_DLLS = {"kernel32.dll", "ntdll.dll", "msvcrt.dll", "bcryptprimitives.dll",
                       "api-ms-win-core-synch-l1-2-0.dll",
                       "userenv.dll", "ws2_32.dll", "advapi32.dll", "bcrypt.dll"}
# Outputs compared between Linux and Wine: every continuous output of the position loop, and the
# solver's counters (which must be equal: the same steps on both systems).
COMPARED_REALS = ["y_pot", "theta_motor", "omega_motor", "p_load", "q_valve", "energy"]
COMPARED_INTEGERS = ["solver.steps", "solver.rejected", "solver.f_evals", "solver.jac_evals",
                     "solver.lu"]


def tool(name, package):
    path = shutil.which(name)
    if path is None:
        pytest.fail(f"{name} is not installed ({package}); run bash tests/setup.sh")
    return path


def member(fmu_path, unzipped, platform, extension, md):
    name = f"binaries/{platform}/{md.coSimulation.modelIdentifier}.{extension}"
    if name not in zipfile.ZipFile(fmu_path).namelist():
        pytest.fail(f"the FMU has no {name}: install the toolchains (bash tests/setup.sh) and run "
                    "`cargo run --release --bin hsp -- package --require-portable`")
    return pathlib.Path(unzipped) / name


def glibc_versions(so):
    """The GLIBC_x.y[.z] versions of the symbols that `so` imports, as tuples."""
    out = subprocess.run([tool("objdump", "binutils"), "-T", str(so)], capture_output=True,
                         text=True, check=True).stdout
    return sorted({tuple(int(p) for p in v.split(".")) for v in re.findall(r"GLIBC_([0-9.]+)", out)})


def test_linux64_needs_at_most_glibc_2_17(fmu_path, unzipped, md):
    so = member(fmu_path, unzipped, "linux64", "so", md)
    versions = glibc_versions(so)
    assert versions, "objdump -T found no GLIBC symbol versions: not a glibc library?"
    newest = versions[-1]
    assert newest <= MAX_GLIBC, (
        f"{so.name} needs GLIBC_{'.'.join(map(str, newest))} (above "
        f"{'.'.join(map(str, MAX_GLIBC))}): it was not built with cargo-zigbuild; symbols: "
        + ", ".join(".".join(map(str, v)) for v in versions))
    private = subprocess.run(["objdump", "-p", str(so)], capture_output=True, text=True,
                             check=True).stdout
    needed = set(re.findall(r"NEEDED\s+(\S+)", private))
    assert needed and needed <= GLIBC_LIBRARIES, f"needs libraries outside glibc: {needed - GLIBC_LIBRARIES}"


def test_glibc_check_reads_a_new_library(fmu_path):
    """The check above can fail: the interpreter running this test links newer glibc symbols."""
    libc = next(pathlib.Path(p) for p in ["/lib/x86_64-linux-gnu/libc.so.6", "/usr/lib64/libc.so.6"]
                if pathlib.Path(p).exists())
    assert glibc_versions(libc)[-1] > MAX_GLIBC


def test_win64_exports_fmi_and_imports_only_system_dlls(fmu_path, unzipped, md):
    dll = member(fmu_path, unzipped, "win64", "dll", md)
    out = subprocess.run([tool("x86_64-w64-mingw32-objdump", "binutils-mingw-w64-x86-64"), "-p",
                          str(dll)], capture_output=True, text=True, check=True).stdout
    imports = {d.lower() for d in re.findall(r"DLL Name: (\S+)", out)}
    assert imports and imports <= WINDOWS_SYSTEM_DLLS, f"non-system DLLs: {imports - WINDOWS_SYSTEM_DLLS}"
    exports = set(re.findall(r"\]\s+(fmi2\w+)", out))
    for f in ["fmi2Instantiate", "fmi2DoStep", "fmi2SerializeFMUstate", "fmi2GetRealStatus",
              "fmi2CancelStep", "fmi2GetVersion"]:
        assert f in exports, f"{f} is not exported"


def read_run(stdout):
    """Lines of driver.c: [(t, {vr: real}, {vr: int})]."""
    rows = []
    for line in stdout.splitlines():
        head, rest = line.split(" r", 1)
        reals, ints = rest.split(" i", 1)
        parse = lambda text, conv: {int(k): conv(v) for k, v in (p.split("=") for p in text.split())}
        rows.append((float(head.split()[1]), parse(reals, float), parse(ints, int)))
    return rows


@pytest.fixture(scope="module")
def drivers(tmp_path_factory):
    """driver.c for Linux (gcc) and for Windows (mingw-w64), and the Wine-only shim DLL."""
    d = tmp_path_factory.mktemp("portable")
    cc, mingw = tool("gcc", "gcc"), tool("x86_64-w64-mingw32-gcc", "gcc-mingw-w64-x86-64")
    flags = ["-O2", "-Wall", "-Wextra", "-Werror"]
    subprocess.run([cc, *flags, "-o", d / "driver", PORTABLE / "driver.c", "-ldl"], check=True)
    subprocess.run([mingw, *flags, "-o", d / "driver.exe", PORTABLE / "driver.c"], check=True)
    subprocess.run([mingw, *flags, "-shared", "-o", d / "bcryptprimitives.dll",
                    PORTABLE / "bcryptprimitives_shim.c", "-ladvapi32"], check=True)
    return d


def driver_args(md, vr, settings=""):
    """driver.c's arguments after the library: the XML's default experiment (1 V step of r),
    every 50th step printed, `settings` (VR:TYPE:VALUE,...) applied before initialisation."""
    stop, step = float(md.defaultExperiment.stopTime), float(md.defaultExperiment.stepSize)
    return [md.guid, repr(stop), repr(step), "1", "50",
            ",".join(str(vr[n]) for n in COMPARED_REALS),
            ",".join(str(vr[n]) for n in COMPARED_INTEGERS)] + ([settings] if settings else [])


def check_rows(md, vr, a, b):
    """Two runs of driver_args printed the same times, every 50 steps, and the solver worked."""
    stop, step = float(md.defaultExperiment.stopTime), float(md.defaultExperiment.stepSize)
    assert len(a) == len(b) == round(stop / step) // 50 + 1
    assert all(t_a == t_b for (t_a, _, _), (t_b, _, _) in zip(a, b))
    assert a[-1][2][vr["solver.steps"]] > 0


def run_both(fmu_path, unzipped, md, vr, drivers, settings=""):
    """The default experiment through the Linux library and through the Windows DLL under Wine,
    with `settings` applied before initialisation; the rows of both runs, every 50 steps."""
    so = member(fmu_path, unzipped, "linux64", "so", md)
    dll = member(fmu_path, unzipped, "win64", "dll", md)
    wine = tool("wine", "wine, wine64")
    shutil.copy(dll, drivers / dll.name)
    args = driver_args(md, vr, settings)
    linux = subprocess.run([drivers / "driver", str(so), *args], capture_output=True, text=True,
                           timeout=300)
    assert linux.returncode == 0, linux.stderr
    # A Wine prefix kept under target/ (ignored by git), made on the first run; no Mono or Gecko
    # installers, and the shim beside driver.exe taken before any built-in bcryptprimitives.
    env = dict(os.environ, WINEPREFIX=str(ROOT / "target" / "wine-prefix"), WINEDEBUG="-all",
               WINEDLLOVERRIDES="mscoree,mshtml=;bcryptprimitives=n,b")
    env.pop("DISPLAY", None)
    windows = subprocess.run([wine, drivers / "driver.exe", dll.name, *args], cwd=drivers,
                             capture_output=True, text=True, timeout=600, env=env)
    assert windows.returncode == 0, windows.stdout[-2000:] + windows.stderr[-4000:]
    a, b = read_run(linux.stdout), read_run(windows.stdout)
    check_rows(md, vr, a, b)
    return a, b


def settings_of(md, vr, values):
    """VR:TYPE:VALUE,... for the driver, each value with its variable's type."""
    kinds = {v.name: v.type for v in md.modelVariables}
    code = {"Real": "r", "Integer": "i", "Enumeration": "i", "Boolean": "b"}  # FMI 2.0 sets an Enumeration as an Integer
    return ",".join(f"{vr[n]}:{code[kinds[n]]}:{int(x) if code[kinds[n]] != 'r' else repr(x)}"
                    for n, x in values.items())


def test_win64_under_wine_matches_linux_bit_for_bit_on_the_loes(fmu_path, unzipped, md, vr,
                                                               drivers):
    # The LOES on the motor alone (preset loes-motor) is linear: its right-hand side calls no
    # math function at all, so both binaries take the same steps and evaluations.
    a, b = run_both(fmu_path, unzipped, md, vr, drivers, settings_of(md, vr, preset("loes-motor")))
    for (t, reals_l, ints_l), (_, reals_w, ints_w) in zip(a, b):
        # The same solver steps and evaluations: the counters are equal, not close.
        assert ints_l == ints_w, f"t = {t}: Linux {ints_l}, Wine {ints_w}"
        assert reals_l == reals_w, f"t = {t}: Linux {reals_l}, Wine {reals_w}"


def test_win64_under_wine_matches_linux_bit_for_bit_on_the_complete_system(fmu_path, unzipped,
                                                                            md, vr, drivers):
    # The FMU's defaults, the complete system, at rtol 1e-10. Its orifices, limits and amplifier
    # call exp, tanh and log1p, and the plate's shape functions sin, cos and exp: from the libm
    # crate compiled into the library (src/math.rs), not from glibc or the Windows C runtime,
    # whose last bits differ and which the adaptive step control would turn into another
    # sequence of steps. So both binaries take the same steps and give the same doubles.
    a, b = run_both(fmu_path, unzipped, md, vr, drivers,
                    settings_of(md, vr, {"solver.rtol": 1e-10, "solver.atol": 1e-10}))
    report_deviation("win64 (Wine) vs Linux, complete system", vr, a, b)
    for (t, reals_l, ints_l), (_, reals_w, ints_w) in zip(a, b):
        assert ints_l == ints_w, f"t = {t}: Linux {ints_l}, Wine {ints_w}"
        assert reals_l == reals_w, f"t = {t}: Linux {reals_l}, Wine {reals_w}"


# ---------------------------------------------------------------------------------------------
# aarch64 Linux (FMI 3.0's binaries/aarch64-linux): glibc 2.17, and run under qemu-aarch64.

FMU3 = ROOT / "fmu" / "fmi3" / "HydraulicSlewingPlate.fmu"
AARCH64_ROOT = pathlib.Path("/usr/aarch64-linux-gnu")
AARCH64_GLIBC_LIBRARIES = (GLIBC_LIBRARIES - {"ld-linux-x86-64.so.2"}) | {"ld-linux-aarch64.so.1"}


@pytest.fixture(scope="module")
def unzipped3(fmu_path, tmp_path_factory):
    """The FMI 3.0 FMU written by the same `hsp package` run as the FMI 2.0 one (the same source
    hash), unzipped."""
    assert packaged_source_hash(FMU3, "x86_64-linux") == packaged_source_hash(fmu_path), FMU3
    d = tmp_path_factory.mktemp("fmu3")
    zipfile.ZipFile(FMU3).extractall(d)
    return d


def test_aarch64_linux_needs_at_most_glibc_2_17(unzipped3, md):
    so = member(FMU3, unzipped3, "aarch64-linux", "so", md)
    # ELF, 64-bit, little-endian, e_machine EM_AARCH64 (183).
    head = so.read_bytes()[:20]
    assert head[:6] == b"\x7fELF\x02\x01" and struct.unpack_from("<H", head, 18)[0] == 183, head
    versions = glibc_versions(so)
    assert versions and versions[-1] <= MAX_GLIBC, versions
    private = subprocess.run(["objdump", "-p", str(so)], capture_output=True, text=True,
                             check=True).stdout
    needed = set(re.findall(r"NEEDED\s+(\S+)", private))
    assert needed and needed <= AARCH64_GLIBC_LIBRARIES, needed - AARCH64_GLIBC_LIBRARIES


@pytest.fixture(scope="module")
def aarch64_driver(tmp_path_factory):
    """driver.c for aarch64 Linux (aarch64-linux-gnu-gcc), run with qemu-aarch64 against the
    aarch64 loader and libc in /usr/aarch64-linux-gnu."""
    d = tmp_path_factory.mktemp("aarch64")
    cc = tool("aarch64-linux-gnu-gcc", "gcc-aarch64-linux-gnu")
    for f in ["lib/ld-linux-aarch64.so.1", "lib/libc.so.6"]:
        if not (AARCH64_ROOT / f).exists():
            pytest.fail(f"{AARCH64_ROOT / f} is missing (libc6-arm64-cross); run bash tests/setup.sh")
    subprocess.run([cc, "-O2", "-Wall", "-Wextra", "-Werror", "-o", d / "driver",
                    PORTABLE / "driver.c", "-ldl"], check=True)
    return d / "driver"


def report_deviation(what, vr, a, b):
    """Prints (pytest -s) the largest difference of each output between two runs, relative to
    its range over the run, and the solver's steps in each: the figures of docs/platforms.md."""
    names = {v: k for k, v in vr.items()}
    scale = {k: max(abs(row[1][k]) for row in a) for k in a[0][1]}
    worst = {names[k]: max(abs(ra[1][k] - rb[1][k]) for ra, rb in zip(a, b)) / scale[k]
             for k in scale}
    steps = vr["solver.steps"]
    print(f"\n{what}: steps {a[-1][2][steps]} and {b[-1][2][steps]}; largest difference / range: "
          + ", ".join(f"{k} {x:.1e}" for k, x in worst.items()))


def run_x86_64_and_aarch64(fmu_path, unzipped, unzipped3, md, vr, drivers, aarch64_driver,
                           settings):
    """The default experiment through the x86-64 Linux library (natively) and through the aarch64
    one (under qemu-aarch64, user-mode emulation), with `settings`; the rows of both runs."""
    x86 = member(fmu_path, unzipped, "linux64", "so", md)
    arm = member(FMU3, unzipped3, "aarch64-linux", "so", md)
    qemu = tool("qemu-aarch64", "qemu-user")
    args = driver_args(md, vr, settings)
    native = subprocess.run([drivers / "driver", str(x86), *args], capture_output=True, text=True,
                            timeout=300)
    assert native.returncode == 0, native.stderr
    emulated = subprocess.run([qemu, "-L", str(AARCH64_ROOT), str(aarch64_driver), str(arm), *args],
                              capture_output=True, text=True, timeout=900)
    assert emulated.returncode == 0, emulated.stderr[-4000:]
    a, b = read_run(native.stdout), read_run(emulated.stdout)
    check_rows(md, vr, a, b)
    return a, b


def test_aarch64_under_qemu_matches_x86_64_bit_for_bit_on_the_loes(fmu_path, unzipped, unzipped3,
                                                                   md, vr, drivers, aarch64_driver):
    # The LOES (preset loes-motor) calls no libm function, and Rust contracts no a*b+c into a
    # fused multiply-add on either processor, so every operation is the same IEEE 754 operation:
    # the two runs take the same steps and print the same numbers, to the last bit (%.17g).
    a, b = run_x86_64_and_aarch64(fmu_path, unzipped, unzipped3, md, vr, drivers, aarch64_driver,
                                  settings_of(md, vr, preset("loes-motor")))
    report_deviation("aarch64 (qemu) vs x86-64, loes-motor", vr, a, b)
    for (t, reals_x, ints_x), (_, reals_a, ints_a) in zip(a, b):
        assert ints_x == ints_a, f"t = {t}: x86-64 {ints_x}, aarch64 {ints_a}"
        assert reals_x == reals_a, f"t = {t}: x86-64 {reals_x}, aarch64 {reals_a}"


def test_aarch64_under_qemu_matches_x86_64_bit_for_bit_on_the_complete_system(
        fmu_path, unzipped, unzipped3, md, vr, drivers, aarch64_driver):
    # The FMU's defaults at rtol 1e-10, as the Wine test: the library's transcendental functions
    # come from the libm crate compiled into it, not from the user's glibc (whose last bits differ
    # between versions, builds and CPUs: on x86-64 glibc picks FMA variants at run time), and its
    # matrix products are summed in a fixed order (nalgebra's go through FMA kernels on aarch64
    # and on x86-64 CPUs that have them). So both processors give the same doubles.
    a, b = run_x86_64_and_aarch64(fmu_path, unzipped, unzipped3, md, vr, drivers, aarch64_driver,
                                  settings_of(md, vr, {"solver.rtol": 1e-10, "solver.atol": 1e-10}))
    report_deviation("aarch64 (qemu) vs x86-64, complete system", vr, a, b)
    for (t, reals_x, ints_x), (_, reals_a, ints_a) in zip(a, b):
        assert ints_x == ints_a, f"t = {t}: x86-64 {ints_x}, aarch64 {ints_a}"
        assert reals_x == reals_a, f"t = {t}: x86-64 {reals_x}, aarch64 {reals_a}"


# ---------------------------------------------------------------------------------------------
# macOS: built and checked here, not run (no Mac). The Mach-O files are read by hand: the fat
# header, each slice's load commands, its symbol table, its export trie and its code signature.

CPU_X86_64, CPU_ARM64 = 0x01000007, 0x0100000C
ARCH_NAMES = {CPU_X86_64: "x86_64", CPU_ARM64: "arm64"}
MH_DYLIB = 6
LC_SYMTAB, LC_ID_DYLIB, LC_CODE_SIGNATURE = 0x2, 0xD, 0x1D
LC_VERSION_MIN_MACOSX, LC_BUILD_VERSION, LC_DYLD_EXPORTS_TRIE = 0x24, 0x32, 0x80000033
LC_DYLD_INFO, LC_DYLD_INFO_ONLY = 0x22, 0x80000022
# Every load command that makes dyld load another library.
LC_DYLIBS = {0xC: "LC_LOAD_DYLIB", 0x80000018: "LC_LOAD_WEAK_DYLIB",
             0x8000001F: "LC_REEXPORT_DYLIB", 0x20: "LC_LAZY_LOAD_DYLIB",
             0x80000023: "LC_LOAD_UPWARD_DYLIB"}
LIBSYSTEM = "/usr/lib/libSystem.B.dylib"


def fat_slices(data):
    """{cputype: bytes} of a universal (fat) file, or of a single Mach-O file."""
    magic = struct.unpack_from(">I", data)[0]
    if magic != 0xCAFEBABE:
        assert struct.unpack_from("<I", data)[0] == 0xFEEDFACF, "neither fat nor 64-bit Mach-O"
        return {struct.unpack_from("<I", data, 4)[0]: data}
    slices = {}
    for i in range(struct.unpack_from(">I", data, 4)[0]):
        cputype, _, offset, size, align = struct.unpack_from(">5I", data, 8 + 20 * i)
        # Each slice starts on its stated alignment (a page: 2^12 or 2^14), as dyld maps it.
        assert align >= 12 and offset % (1 << align) == 0, (hex(cputype), offset, align)
        slices[cputype] = data[offset:offset + size]
    return slices


def version(v):
    """A Mach-O version (xxxx.yy.zz in nibbles) as 'major.minor'."""
    return f"{v >> 16}.{(v >> 8) & 0xFF}"


def uleb(data, at):
    value, shift = 0, 0
    while True:
        byte = data[at]
        at += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if byte < 0x80:
            return value, at


def export_trie(data, start, size):
    """The names in an export trie (what dlsym finds): each node is a ULEB128 size of its
    terminal information (non-zero: a name ends here), that information, a count of children,
    and per child its edge label (a C string) and the ULEB128 offset of its node."""
    names, stack = [], [(start, "")]
    while stack:
        node, prefix = stack.pop()
        terminal, at = uleb(data, node)
        if terminal:
            names.append(prefix)
        at += terminal
        children, at = data[at], at + 1
        for _ in range(children):
            end = data.index(b"\0", at)
            label = data[at:end].decode()
            child, at = uleb(data, end + 1)
            assert child < size, "export trie child out of range"
            stack.append((start + child, prefix + label))
    return names


def macho(data):
    """The facts of one 64-bit little-endian Mach-O slice that the tests check."""
    magic, cputype, _, filetype, ncmds, _, flags, _ = struct.unpack_from("<8I", data)
    assert magic == 0xFEEDFACF
    facts = {"cputype": cputype, "filetype": filetype, "flags": flags, "dylibs": [],
             "minos": None, "signature": None, "id": None}
    at = 32
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<2I", data, at)
        if cmd in LC_DYLIBS or cmd == LC_ID_DYLIB:
            name_at = struct.unpack_from("<I", data, at + 8)[0]
            name = data[at + name_at:at + size].split(b"\0")[0].decode()
            if cmd == LC_ID_DYLIB:
                facts["id"] = name
            else:
                facts["dylibs"].append((LC_DYLIBS[cmd], name))
        elif cmd == LC_BUILD_VERSION:
            facts["minos"] = version(struct.unpack_from("<I", data, at + 12)[0])
        elif cmd == LC_VERSION_MIN_MACOSX:
            facts["minos"] = version(struct.unpack_from("<I", data, at + 8)[0])
        elif cmd == LC_CODE_SIGNATURE:
            facts["signature"] = struct.unpack_from("<2I", data, at + 8)
        elif cmd == LC_SYMTAB:
            facts["symtab"] = struct.unpack_from("<4I", data, at + 8)
        elif cmd in (LC_DYLD_INFO, LC_DYLD_INFO_ONLY):
            facts["exports_at"] = struct.unpack_from("<2I", data, at + 40)
        elif cmd == LC_DYLD_EXPORTS_TRIE:
            facts["exports_at"] = struct.unpack_from("<2I", data, at + 8)
        at += size
    symoff, nsyms, stroff, _ = facts["symtab"]
    facts["undefined"] = []  # (name, library ordinal)
    for i in range(nsyms):
        strx, ntype, _, desc, _ = struct.unpack_from("<IBBHQ", data, symoff + 16 * i)
        if ntype & 0xE0 == 0 and ntype & 0x0E == 0 and ntype & 0x01:  # external, undefined
            name = data[stroff + strx:data.index(b"\0", stroff + strx)].decode()
            facts["undefined"].append((name, (desc >> 8) & 0xFF))
    offset, size = facts["exports_at"]
    facts["exports"] = export_trie(data, offset, size)
    return facts


def code_signature_is_valid(data, facts):
    """The ad-hoc signature's code directory hashes every page of the slice up to its code
    limit: recompute them (SHA-256 or SHA-1, as the directory says)."""
    offset, _ = facts["signature"]
    magic, _, count = struct.unpack_from(">3I", data, offset)
    assert magic == 0xFADE0CC0, "no embedded signature super blob"
    for i in range(count):
        slot, blob = struct.unpack_from(">2I", data, offset + 12 + 8 * i)
        cd = offset + blob
        if slot != 0:  # the code directory is slot 0
            continue
        (magic, _, _, flags, hash_at, _, _, n_code, code_limit,
         hash_size, hash_type, _, page_log) = struct.unpack_from(">9I4B", data, cd)
        assert magic == 0xFADE0C02 and flags & 0x2, "not an ad-hoc code directory"
        algorithm = {1: "sha1", 2: "sha256"}[hash_type]
        page = 1 << page_log
        for k in range(n_code):
            chunk = data[k * page:min((k + 1) * page, code_limit)]
            stored = data[cd + hash_at + k * hash_size:cd + hash_at + (k + 1) * hash_size]
            if hashlib.new(algorithm, chunk).digest()[:hash_size] != stored:
                return False
        return n_code == -(-code_limit // page)
    return False


def deployment_target(target):
    """The minimum macOS rustc compiles `target` for: what each slice must state."""
    out = subprocess.run(["rustc", "--print", "deployment-target", "--target", target],
                         capture_output=True, text=True, check=True).stdout
    return out.strip().split("=")[1]


def fmi_exports_of_linux_library(fmu_path, unzipped, md):
    so = member(fmu_path, unzipped, "linux64", "so", md)
    out = subprocess.run(["objdump", "-T", str(so)], capture_output=True, text=True,
                         check=True).stdout
    return {line.split()[-1] for line in out.splitlines()
            if " .text" in line and line.split()[-1].startswith(("fmi2", "fmi3"))}


@pytest.fixture(scope="module")
def mac_binaries(fmu_path, unzipped, unzipped3, md):
    """{"darwin64": universal bytes, "x86_64-darwin": ..., "aarch64-darwin": ...}."""
    return {platform: member(fmu, d, platform, "dylib", md).read_bytes()
            for fmu, d, platform in [(fmu_path, unzipped, "darwin64"),
                                     (FMU3, unzipped3, "x86_64-darwin"),
                                     (FMU3, unzipped3, "aarch64-darwin")]}


def test_darwin64_is_universal_and_the_fmi3_folders_hold_its_slices(mac_binaries, md):
    fat = fat_slices(mac_binaries["darwin64"])
    assert set(fat) == {CPU_X86_64, CPU_ARM64}, [hex(c) for c in fat]
    for platform, cpu in [("x86_64-darwin", CPU_X86_64), ("aarch64-darwin", CPU_ARM64)]:
        thin = fat_slices(mac_binaries[platform])
        assert list(thin) == [cpu], (platform, [hex(c) for c in thin])
        # The same build: FMI 3.0's single-architecture file is the universal file's slice.
        assert thin[cpu] == fat[cpu], platform
        facts = macho(thin[cpu])
        assert facts["filetype"] == MH_DYLIB and facts["cputype"] == cpu
        # Its install name is its name in the FMU, not the build machine's path.
        assert facts["id"] == f"@rpath/{md.coSimulation.modelIdentifier}.dylib", facts["id"]


@pytest.mark.parametrize("cpu, target", [(CPU_X86_64, "x86_64-apple-darwin"),
                                         (CPU_ARM64, "aarch64-apple-darwin")])
def test_darwin_slice_exports_fmi_needs_only_libsystem_and_states_its_minimum_macos(
        mac_binaries, fmu_path, unzipped, md, cpu, target):
    data = fat_slices(mac_binaries["darwin64"])[cpu]
    facts = macho(data)
    # Every fmi2*/fmi3* function the Linux library exports, found by dlsym (the export trie; C
    # names carry a leading underscore in Mach-O).
    exported = {name[1:] for name in facts["exports"] if name.startswith(("_fmi2", "_fmi3"))}
    expected = fmi_exports_of_linux_library(fmu_path, unzipped, md)
    assert len(expected) > 80 and exported == expected, sorted(expected ^ exported)
    # One library: libSystem, which every macOS has (libc, libm, libpthread, dyld are in it).
    assert facts["dylibs"] == [("LC_LOAD_DYLIB", LIBSYSTEM)], facts["dylibs"]
    # Every undefined symbol is looked up in it (two-level namespace: library ordinal 1).
    assert facts["undefined"] and all(o == 1 for _, o in facts["undefined"]), \
        [u for u in facts["undefined"] if u[1] != 1]
    # The minimum macOS the slice states is the one rustc compiled it for (not zig's default).
    assert facts["minos"] == deployment_target(target), facts["minos"]
    print(f"\n{target}: {len(data)} bytes, minimum macOS {facts['minos']}, "
          f"{len(facts['undefined'])} symbols from libSystem, {len(facts['exports'])} exported "
          f"({len(exported)} fmi2*/fmi3*)")


def test_darwin_arm64_slice_has_a_valid_ad_hoc_signature(mac_binaries):
    # Apple silicon refuses to run unsigned code; an ad-hoc signature (no identity) suffices.
    data = fat_slices(mac_binaries["darwin64"])[CPU_ARM64]
    facts = macho(data)
    assert facts["signature"] is not None, "no LC_CODE_SIGNATURE"
    assert code_signature_is_valid(data, facts)
    # The check can fail: one changed byte of code breaks the page's hash.
    broken = bytearray(data)
    broken[0x4000] ^= 1
    assert not code_signature_is_valid(bytes(broken), facts)


@pytest.mark.parametrize("cpu", [CPU_X86_64, CPU_ARM64])
def test_darwin_slice_exports_only_fmi(mac_binaries, cpu):
    # As the Linux library (its version script): only fmi2*/fmi3* are exported. rustc hands the
    # linker that list; a linker that ignores it (zig 0.17's did) exports every Rust symbol.
    facts = macho(fat_slices(mac_binaries["darwin64"])[cpu])
    extra = [n for n in facts["exports"] if not n.startswith(("_fmi2", "_fmi3"))]
    assert not extra, f"{len(extra)} other symbols exported, e.g. {extra[:3]}"
