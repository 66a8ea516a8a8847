"""The README's first command on a machine that has only the host's Rust toolchain.

`cargo run --release --bin hsp -- run` must build the FMU and run the default experiment without
any optional toolchain: no cross targets, no WebAssembly target, no zig, no `.venv`. The test makes
that machine inside this one:

- a copy of the checkout's files (what `git clone` gives: tracked and new files, no `target/`,
  no `.venv`, no built page module);
- a `RUSTC` wrapper that runs this rustc with a sysroot holding the host's standard library only,
  so that every other target is really absent (`rustc --print sysroot` names that sysroot, and a
  build for another target would fail);
- a `PATH` without the checkout's `.venv/bin` (no cargo-zigbuild, no zig).

It asserts success, one warning for each optional product naming what is missing and how to add
it, no half-written archive left behind, the summary and the plot, and an FMU that fmpy loads
and runs. A second run with `--require-portable` must fail, name the missing toolchain and leave
nothing half-written either.
"""

import os
import pathlib
import shutil
import subprocess
import zipfile

import pytest
from fmpy import read_model_description, simulate_fmu

ROOT = pathlib.Path(__file__).resolve().parents[2]
HOST = "x86_64-unknown-linux-gnu"

# What each optional product's warning must name: the missing piece and the command that adds it.
WARNINGS = {
    "browser page": ["wasm32-unknown-unknown", "rustup target add wasm32-unknown-unknown",
                     "no browser page"],
    "glibc 2.17 Linux binary": ["cargo-zigbuild", "glibc 2.17", "tests/setup.sh"],
    "aarch64 Linux binary": ["binaries/aarch64-linux", "tests/setup.sh"],
    "Windows binary": ["rustup target add x86_64-pc-windows-gnu", "binaries/win64"],
    "macOS binaries": ["rustup target add x86_64-apple-darwin aarch64-apple-darwin",
                       "binaries/darwin64"],
    "WebAssembly component": ["rustup target add wasm32-wasip2", "binaries/wasm32-wasip2"],
}


@pytest.fixture(scope="module")
def bare(tmp_path_factory):
    """A fresh checkout and a toolchain without the optional targets: (checkout, environment)."""
    base = tmp_path_factory.mktemp("first-command")
    checkout = base / "checkout"
    files = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT, capture_output=True, check=True).stdout.decode().split("\0")
    for name in filter(None, files):
        source = ROOT / name
        if source.is_file():
            (checkout / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, checkout / name)
    assert not (checkout / ".venv").exists() and not (checkout / "docs/web/hsp.wasm").exists()

    real_rustc = shutil.which("rustc")
    sysroot = subprocess.run([real_rustc, "--print", "sysroot"], capture_output=True, text=True,
                             check=True).stdout.strip()
    bare_sysroot = base / "sysroot"
    (bare_sysroot / "lib/rustlib").mkdir(parents=True)
    (bare_sysroot / "lib/rustlib" / HOST).symlink_to(pathlib.Path(sysroot, "lib/rustlib", HOST))
    wrapper = base / "bin" / "rustc"
    wrapper.parent.mkdir()
    wrapper.write_text(f'#!/bin/sh\nexec "{real_rustc}" --sysroot "{bare_sysroot}" "$@"\n')
    wrapper.chmod(0o755)

    env = dict(os.environ)
    venv_bin = str(ROOT / ".venv" / "bin")
    env["PATH"] = os.pathsep.join(p for p in env["PATH"].split(os.pathsep)
                                  if p and pathlib.Path(p) != pathlib.Path(venv_bin))
    env.pop("VIRTUAL_ENV", None)
    env["RUSTC"] = str(wrapper)
    # A target directory of its own, so that the checkout's builds are not disturbed.
    env["CARGO_TARGET_DIR"] = str(base / "target")
    for name in ("CARGO_BUILD_TARGET", "RUSTFLAGS", "CARGO_ENCODED_RUSTFLAGS"):
        env.pop(name, None)

    printed = subprocess.run([str(wrapper), "--print", "sysroot"], capture_output=True,
                             text=True, check=True, env=env).stdout.strip()
    assert printed == str(bare_sysroot)
    assert not (bare_sysroot / "lib/rustlib/wasm32-unknown-unknown").exists()
    return checkout, env


@pytest.fixture(scope="module")
def first_command(bare):
    checkout, env = bare
    done = subprocess.run(["cargo", "run", "--release", "--bin", "hsp", "--", "run"],
                          cwd=checkout, env=env, capture_output=True, text=True, timeout=1500)
    return checkout, done


def partial_files(checkout):
    return sorted(str(p.relative_to(checkout)) for p in checkout.rglob("*.partial"))


def test_first_command_succeeds_with_one_warning_per_optional_product(first_command):
    checkout, done = first_command
    assert done.returncode == 0, done.stderr[-3000:]
    warnings = [line for line in done.stderr.splitlines() if line.startswith("warning: ")]
    for product, words in WARNINGS.items():
        matching = [w for w in warnings if all(word in w for word in words)]
        assert len(matching) == 1, f"{product}: expected one warning naming {words}, got {warnings}"
    assert len(warnings) == len(WARNINGS), warnings
    assert partial_files(checkout) == []


def test_first_command_prints_the_summary_and_writes_the_results_and_plot(first_command):
    checkout, done = first_command
    assert done.returncode == 0, done.stderr[-3000:]
    out = done.stdout
    for heading in ("motor", "hub", "tip", "validity", "solver", "results", "plots"):
        assert f"\n  {heading} " in out, f"no {heading!r} line in\n{out}"
    assert "no warning: the loop is damped and the run stays within the linear model's range" in out
    results = checkout / "results"
    assert (results / "default_experiment.csv").stat().st_size > 100_000
    png = (results / "default_experiment.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000


def test_the_fmus_hold_the_host_binary_and_no_page_and_fmpy_runs_them(first_command):
    checkout, done = first_command
    assert done.returncode == 0, done.stderr[-3000:]
    fmu2 = checkout / "fmu" / "HydraulicSlewingPlate.fmu"
    fmu3 = checkout / "fmu" / "fmi3" / "HydraulicSlewingPlate.fmu"
    csv = (checkout / "results" / "default_experiment.csv").read_text().splitlines()
    final = dict(zip(csv[0].split(","), map(float, csv[-1].split(","))))
    assert final["time"] == 6.0
    for fmu, platform in ((fmu2, "linux64"), (fmu3, "x86_64-linux")):
        with zipfile.ZipFile(fmu) as z:
            names = z.namelist()
            binaries = sorted({n.split("/")[1] for n in names if n.startswith("binaries/")})
            assert binaries == [platform], (fmu, binaries)
            assert not any(n.startswith("documentation/web/") for n in names)
            assert "web/index.html" not in z.read("documentation/index.html").decode()
        md = read_model_description(str(fmu))
        assert md.coSimulation is not None and md.modelExchange is not None
        # The default experiment again, through fmpy: the final hub angle of `hsp run`'s CSV.
        res = simulate_fmu(str(fmu), stop_time=6.0, output_interval=5e-3,
                           output=["theta_hub", "w_tip"])
        assert res["theta_hub"][-1] == pytest.approx(final["theta_hub"], rel=1e-9)
        assert res["w_tip"][-1] == pytest.approx(final["w_tip"], rel=1e-9)
    assert (checkout / "fmu" / "HydraulicSlewingPlate.ssp").is_file()
    assert not (checkout / "docs/web/hsp.wasm").exists()


def test_require_portable_fails_naming_the_toolchain_and_leaves_nothing_half_written(
        bare, first_command):
    checkout, env = bare
    done = subprocess.run(["cargo", "run", "--release", "--quiet", "--bin", "hsp", "--",
                           "package", "--require-portable", "--output", "fmu/strict.fmu"],
                          cwd=checkout, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode != 0
    assert "cargo-zigbuild" in done.stderr and "glibc 2.17" in done.stderr, done.stderr
    assert not (checkout / "fmu" / "strict.fmu").exists()
    assert partial_files(checkout) == []
