"""The FMU's binaries on other systems than the build machine.

- binaries/linux64 is linked against glibc 2.17 (hsp package, cargo-zigbuild): objdump -T lists no
  symbol version above GLIBC_2.17 and objdump -p needs no library outside glibc.
- binaries/win64 (cross-compiled with mingw-w64) exports the FMI functions, imports only system
  DLLs, and under Wine runs the default experiment to the same result as the Linux library: the
  same driver (tests/portable/driver.c) is built for both with gcc and mingw-w64.

What this does not test: Windows itself (Wine is not Windows: its loader, its C runtime and its
math library differ; the DLL imports ProcessPrng from bcryptprimitives.dll, which Windows 10 and
later have and Debian's Wine 8 lacks, so a test-only shim stands in for it here,
tests/portable/bcryptprimitives_shim.c), importers other than this driver on Windows, and old
Linux distributions themselves (only the symbol versions the library asks for).

Every tool comes from tests/setup.sh; a missing one fails the test with what to install."""

import os
import pathlib
import re
import shutil
import subprocess
import zipfile

import pytest

from conftest import preset

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


def run_both(fmu_path, unzipped, md, vr, drivers, settings=""):
    """The default experiment (1 V step of r, the XML's DefaultExperiment) through the Linux
    library and through the Windows DLL under Wine, with `settings` (VR:TYPE:VALUE,...) applied
    before initialisation; the rows of both runs, every 50 steps."""
    so = member(fmu_path, unzipped, "linux64", "so", md)
    dll = member(fmu_path, unzipped, "win64", "dll", md)
    wine = tool("wine", "wine, wine64")
    shutil.copy(dll, drivers / dll.name)
    stop, step = float(md.defaultExperiment.stopTime), float(md.defaultExperiment.stepSize)
    args = [md.guid, repr(stop), repr(step), "1", "50",
            ",".join(str(vr[n]) for n in COMPARED_REALS),
            ",".join(str(vr[n]) for n in COMPARED_INTEGERS)] + ([settings] if settings else [])
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
    assert len(a) == len(b) == round(stop / step) // 50 + 1
    assert all(t_l == t_w for (t_l, _, _), (t_w, _, _) in zip(a, b))
    assert a[-1][2][vr["solver.steps"]] > 0
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
    # libm function, so both binaries take the same steps and evaluations, and agree to 1e-9.
    a, b = run_both(fmu_path, unzipped, md, vr, drivers, settings_of(md, vr, preset("loes-motor")))
    scale = {k: max(abs(row[1][k]) for row in a) for k in a[0][1]}
    for (t, reals_l, ints_l), (_, reals_w, ints_w) in zip(a, b):
        # The same solver steps and evaluations: the counters are equal, not close.
        assert ints_l == ints_w, f"t = {t}: Linux {ints_l}, Wine {ints_w}"
        for k, x in reals_l.items():
            assert abs(x - reals_w[k]) <= 1e-9 * scale[k], (t, k, x, reals_w[k])


def test_win64_under_wine_matches_linux_on_the_complete_system(fmu_path, unzipped, md, vr,
                                                               drivers):
    # The FMU's defaults, the complete system, at rtol 1e-10. Its orifices, limits and amplifier
    # call sqrt, exp, tanh and log, whose last bits differ between glibc's libm and the Windows
    # C runtime's; the adaptive step control turns that into a different sequence of steps, so
    # the results agree to the integrator's accuracy, not bit for bit: both lie within about
    # rtol of the exact solution, asserted here as 1e-7 of each output's range over the run. The
    # absolute tolerance goes down with rtol (it is a fraction of each state's nominal value,
    # 10 rad/s for the rotor, far above the default move's speeds): at the default 1e-8 it, not
    # rtol, would bound the accuracy.
    a, b = run_both(fmu_path, unzipped, md, vr, drivers,
                    settings_of(md, vr, {"solver.rtol": 1e-10, "solver.atol": 1e-10}))
    scale = {k: max(abs(row[1][k]) for row in a) for k in a[0][1]}
    for (t, reals_l, _), (_, reals_w, _) in zip(a, b):
        for k in scale:
            assert abs(reals_l[k] - reals_w[k]) <= 1e-7 * scale[k], (t, k, reals_l[k], reals_w[k])
